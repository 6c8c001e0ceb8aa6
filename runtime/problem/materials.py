"""Materials of a rod problem and the rod's stiffness and damping they give.

``kelvin_voigt`` (the paper): ``density`` (kg/m^3), ``youngs_modulus`` E (Pa),
``poisson_ratio`` nu, and the viscosity as retardation times ``tau_S`` (shear) and
``tau_B`` (bulk) in s, or ``tau`` (the paper's convention tau_S = tau_B = tau), or the
viscosities ``eta`` (shear, Pa s) and ``zeta`` (bulk, Pa s); ``damping = "consistent"``
(eta_E from the dissipation function, eqs. (4)-(9)) or ``"naive"`` (the stress-resultant
route's eta~_E). ``density_end`` and ``youngs_modulus_end`` make them vary linearly along
the rod. The rod's matrices C_F, C_M (eq. (7)) and V_F, V_M (eq. (9)) come from
``generated/constitutive.py``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.problem import coerce as C
from runtime.problem.sections import GivenStiffness, Section, Shape

DAMPING_ROUTES = ("consistent", "naive")


def _constitutive():
    from generated import constitutive

    return constitutive


@dataclass(frozen=True)
class KelvinVoigt:
    """Kelvin-Voigt material (see the module docstring); SI units."""

    density: float = 1000.0
    youngs_modulus: float = 1.0e6
    poisson_ratio: float = 0.3
    tau_S: float = 0.0
    tau_B: float = 0.0
    damping: str = "consistent"
    density_end: float | None = None
    youngs_modulus_end: float | None = None
    model: str = "kelvin_voigt"

    def __post_init__(self) -> None:
        C.positive("material.density", self.density)
        C.positive("material.youngs_modulus", self.youngs_modulus)
        C.number("material.poisson_ratio", self.poisson_ratio, low=-1.0, high=0.5,
                 low_incl=False, allowed="-1 < nu <= 1/2")
        C.nonnegative("material.tau_S", self.tau_S)
        C.nonnegative("material.tau_B", self.tau_B)
        C.choice("material.damping", self.damping, DAMPING_ROUTES)
        if self.density_end is not None:
            C.positive("material.density_end", self.density_end)
        if self.youngs_modulus_end is not None:
            C.positive("material.youngs_modulus_end", self.youngs_modulus_end)

    @property
    def tau_E(self) -> float:
        """Extensional retardation time (6) of the consistent route, or tau~_E (s)."""
        c = _constitutive()
        if self.damping == "consistent":
            return float(c.retardation_time_extension(self.tau_B, self.tau_S,
                                                      self.poisson_ratio))
        return float(c.retardation_time_extension_naive(self.tau_B, self.tau_S))

    def at(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(density, E) at the fractions ``x`` of the length."""
        x = np.asarray(x, dtype=float)
        rho_b = self.density if self.density_end is None else self.density_end
        E_b = self.youngs_modulus if self.youngs_modulus_end is None else self.youngs_modulus_end
        return (self.density + (rho_b - self.density) * x,
                self.youngs_modulus + (E_b - self.youngs_modulus) * x)

    def rod_matrices(self, section: Section, x: np.ndarray) -> dict[str, np.ndarray]:
        """Per segment (at fractions x of the length): diagonals C_F, C_M, V_F, V_M (n, 3)
        and rhoA (n,), rhoI (n, 3)."""
        c = _constitutive()
        nu = self.poisson_ratio
        x = np.atleast_1d(np.asarray(x, dtype=float))
        if isinstance(section, GivenStiffness):
            s = section
            CF = np.tile([s.GA1, s.GA2, s.EA], (x.size, 1))
            CM = np.tile([s.EI1, s.EI2, s.GJ], (x.size, 1))
            tS, tE = self.tau_S, self.tau_E
            return {"C_F": CF, "C_M": CM, "V_F": CF * [tS, tS, tE], "V_M": CM * [tE, tE, tS],
                    "rhoA": np.full(x.size, s.rhoA),
                    "rhoI": np.tile([s.rhoI1, s.rhoI2, s.rhoI3], (x.size, 1))}
        assert isinstance(section, Shape)
        k = section.constants(nu, x)
        rho, E = self.at(x)
        out = {n: np.empty((x.size, 3)) for n in ("C_F", "C_M", "V_F", "V_M")}
        for i in range(x.size):
            geo = tuple(float(k[n][i]) for n in ("A", "I1", "I2", "I3", "kappa_1", "kappa_2",
                                                 "kappa_3"))
            CF, CM = c.stiffness_matrices(float(E[i]), nu, *geo)
            VF, VM = c.damping_matrices(float(E[i]), nu, self.tau_S, self.tau_B, *geo,
                                        route=self.damping)
            for name, mat in (("C_F", CF), ("C_M", CM), ("V_F", VF), ("V_M", VM)):
                mat = np.asarray(mat, dtype=float)
                if np.any(mat - np.diag(np.diag(mat))):   # pragma: no cover - eq. (7), (9)
                    raise ValueError(f"{name} is not diagonal; the kernels take diagonals")
                out[name][i] = np.diag(mat)
        out["rhoA"] = rho * k["A"]
        out["rhoI"] = rho[:, None] * np.column_stack([k["I1"], k["I2"], k["I3"]])
        return out

    def to_mapping(self) -> dict[str, Any]:
        out = {"model": "kelvin_voigt", "density": self.density,
               "youngs_modulus": self.youngs_modulus, "poisson_ratio": self.poisson_ratio,
               "tau_S": self.tau_S, "tau_B": self.tau_B, "damping": self.damping}
        if self.density_end is not None:
            out["density_end"] = self.density_end
        if self.youngs_modulus_end is not None:
            out["youngs_modulus_end"] = self.youngs_modulus_end
        return out


Material = KelvinVoigt
MODELS = ("kelvin_voigt",)
_KV_KEYS = ("model", "density", "youngs_modulus", "poisson_ratio", "tau", "tau_S", "tau_B",
            "eta", "zeta", "damping", "density_end", "youngs_modulus_end")


def material_from_mapping(m: Mapping[str, Any] | None) -> Material:
    """A material from ``[material]`` (see the module docstring)."""
    m = dict(C.table("material", m if m is not None else {}))
    model = C.choice("material.model", m.get("model", "kelvin_voigt"), MODELS)
    C.no_unknown_keys("material", m, _KV_KEYS)
    C.exclusive("material", m, ("tau",), ("tau_S", "tau_B"), ("eta", "zeta"))
    kw: dict[str, Any] = {}
    for key in ("density", "youngs_modulus", "poisson_ratio", "density_end",
                "youngs_modulus_end"):
        if key in m:
            kw[key] = C.number(f"material.{key}", m[key])
    if "damping" in m:
        kw["damping"] = m["damping"]
    if "tau" in m:
        kw["tau_S"] = kw["tau_B"] = C.nonnegative("material.tau", m["tau"])
    for key in ("tau_S", "tau_B"):
        if key in m:
            kw[key] = C.nonnegative(f"material.{key}", m[key])
    if "eta" in m or "zeta" in m:
        c = _constitutive()
        E = kw.get("youngs_modulus", KelvinVoigt.youngs_modulus)
        nu = kw.get("poisson_ratio", KelvinVoigt.poisson_ratio)
        if "eta" in m:
            kw["tau_S"] = C.nonnegative("material.eta", m["eta"]) / float(c.shear_modulus(E, nu))
        if "zeta" in m:
            zeta = C.nonnegative("material.zeta", m["zeta"])
            if nu >= 0.5 and zeta > 0:
                raise ParameterError("material.zeta", zeta, "0 for an incompressible material "
                                     "(nu = 1/2: the bulk modulus is infinite)")
            kw["tau_B"] = 0.0 if zeta == 0 else zeta / float(c.bulk_modulus(E, nu))
    if model == "kelvin_voigt":
        return KelvinVoigt(**kw)
    raise ParameterError("material.model", model, "one of " + ", ".join(MODELS))  # pragma: no cover


def joint_average(per_segment: np.ndarray) -> np.ndarray:
    """Joint values (N+1, ...) from segment values (N, ...): the mean of the two adjacent
    segments inside, the end segment's value at the ends (the clamp joints)."""
    a = np.asarray(per_segment, dtype=float)
    out = np.empty((a.shape[0] + 1,) + a.shape[1:])
    out[0], out[-1] = a[0], a[-1]
    out[1:-1] = 0.5 * (a[:-1] + a[1:])
    return out
