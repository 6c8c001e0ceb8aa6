"""Materials of a rod problem and the rod's stiffness and damping they give.

Two models (TOML ``[material] model = ...``):

``kelvin_voigt`` (the paper): ``density`` (kg/m^3), ``youngs_modulus`` E (Pa),
``poisson_ratio`` nu, and the viscosity as retardation times ``tau_S`` (shear) and
``tau_B`` (bulk) in s, or ``tau`` (the paper's convention tau_S = tau_B = tau), or the
viscosities ``eta`` (shear, Pa s) and ``zeta`` (bulk, Pa s). The rod viscosity route,
``"consistent"`` (eta_E from the dissipation function, eqs. (4)-(9)) or ``"naive"`` (the
stress-resultant route's eta~_E), is the key ``section.damping``; ``material.damping``, its
place before composite sections, is still read, and the problem keeps the route here
(``KelvinVoigt.damping``). ``density_end`` and ``youngs_modulus_end`` make them vary
linearly along the rod. The rod's matrices C_F, C_M (eq. (7)) and V_F, V_M (eq. (9)) come from
``generated/constitutive.py``.

``generalized_maxwell`` (the paper's future work, Sect. 6): the 3-D solid of an equilibrium
spring (``youngs_modulus``, ``poisson_ratio``: E_inf, nu_inf) and M Maxwell branches
``[[material.branches]]``, each with ``tau`` (s) and either ``youngs_modulus`` and
``poisson_ratio`` or ``shear_modulus`` and ``bulk_modulus`` (Pa). Extension and bending
of the rod carry the uniaxial relaxation function of that solid, shear and torsion its
shear relaxation function; both are Prony series with up to 2M terms (derivation step
``maxwell_rod``; ``generated/constitutive.py``, ``maxwell_rod_prony``), which become the
rod's relaxation terms: per term b a relaxation time theta_b and moduli on every segment
and joint, each carrying an internal strain (``generated/rod_layout.py``). The section's
shear factors use the equilibrium nu. ``density_end`` varies the density linearly.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from runtime.errors import ParameterError
from runtime.problem import coerce as C
from runtime.problem.sections import (
    COMPOSITE_REFUSAL,
    DAMPING_ROUTES,
    Composite,
    GivenStiffness,
    Section,
    Shape,
)
from runtime.section.materials import check_wave_speed
from runtime.sorted_sets import sorted_union

#: DAMPING_ROUTES lives in runtime.problem.sections (the key is section.damping); imported
#: here for the material's own checks and the older imports


def _refuse_composite(section: Section) -> None:
    if isinstance(section, Composite):
        raise ParameterError("section.kind", "composite", COMPOSITE_REFUSAL)


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
        check_wave_speed(self.youngs_modulus, self.density, "material.youngs_modulus",
                         "material.density")
        if self.youngs_modulus_end is not None or self.density_end is not None:
            E_end = self.youngs_modulus_end
            rho_end = self.density_end
            check_wave_speed(self.youngs_modulus if E_end is None else E_end,
                             self.density if rho_end is None else rho_end,
                             "material.youngs_modulus" + ("" if E_end is None else "_end"),
                             "material.density" + ("" if rho_end is None else "_end"))

    @property
    def tau_E(self) -> float:
        """Extensional retardation time (6) of the consistent route, or tau~_E (s)."""
        c = _constitutive()
        if self.damping == "consistent":
            return float(c.retardation_time_extension(self.tau_B, self.tau_S,
                                                      self.poisson_ratio))
        return float(c.retardation_time_extension_naive(self.tau_B, self.tau_S))

    def describe(self) -> str:
        """One line for reports: the retardation times."""
        return (f"Kelvin-Voigt, tau_S = {self.tau_S} s, tau_B = {self.tau_B} s "
                f"(tau_E = {self.tau_E:.6g} s, {self.damping})")

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
        _refuse_composite(section)
        c = _constitutive()
        nu = self.poisson_ratio
        x = np.atleast_1d(np.asarray(x, dtype=float))
        if isinstance(section, GivenStiffness):
            s = section
            tS, tE = self.tau_S, self.tau_E
            if s.coupled or s.viscosity_matrix is not None:
                from runtime.problem.coupled import given_matrices

                out = given_matrices(s, np.array([tS, tS, tE, tE, tE, tS]), x.size)
                if not s.coupled:     # diagonal after all: the diagonal kernels take it
                    out = {k: out[k] for k in ("C_F", "C_M", "V_F", "V_M", "rhoA", "rhoI")}
                return out
            CF = np.tile([s.GA1, s.GA2, s.EA], (x.size, 1))
            CM = np.tile([s.EI1, s.EI2, s.GJ], (x.size, 1))
            return {"C_F": CF, "C_M": CM, "V_F": CF * [tS, tS, tE], "V_M": CM * [tE, tE, tS],
                    "rhoA": np.full(x.size, s.rhoA),
                    "rhoI": np.tile([s.rhoI1, s.rhoI2, s.rhoI3], (x.size, 1))}
        assert isinstance(section, Shape)
        k = section.constants(nu, x)
        rho, E = self.at(x)
        out = {n: np.empty((x.size, 3)) for n in ("C_F", "C_M", "V_F", "V_M")}
        # a uniform rod evaluates the formulas once: segment i takes the values of the
        # first segment with its (E, geometry)
        keys = np.column_stack([np.broadcast_to(np.asarray(v, dtype=float), x.shape)
                                for v in (E, *(k[n] for n in ("A", "I1", "I2", "I3", "kappa_1",
                                                              "kappa_2", "kappa_3")))])
        done: dict[tuple, int] = {}
        source = np.empty(x.size, dtype=int)
        for i, key in enumerate(map(tuple, keys.tolist())):
            source[i] = done.setdefault(key, i)
            if source[i] != i:
                continue
            geo = key[1:]
            CF, CM = c.stiffness_matrices(key[0], nu, *geo)
            VF, VM = c.damping_matrices(key[0], nu, self.tau_S, self.tau_B, *geo,
                                        route=self.damping)
            for name, mat in (("C_F", CF), ("C_M", CM), ("V_F", VF), ("V_M", VM)):
                mat = np.asarray(mat, dtype=float)
                if np.any(mat - np.diag(np.diag(mat))):   # pragma: no cover - eq. (7), (9)
                    raise ValueError(f"{name} is not diagonal; the kernels take diagonals")
                out[name][i] = np.diag(mat)
        for name in out:
            out[name][:] = out[name][source]
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


@dataclass(frozen=True)
class Branch:
    """One Maxwell branch of the 3-D solid: shear and bulk moduli (Pa), relaxation time (s)."""

    shear_modulus: float
    bulk_modulus: float
    tau: float

    def to_mapping(self) -> dict[str, Any]:
        return {"shear_modulus": self.shear_modulus, "bulk_modulus": self.bulk_modulus,
                "tau": self.tau}


@dataclass(frozen=True)
class RodRelaxation:
    """The rod-level Prony series of a generalized Maxwell material: relaxation times
    ``theta`` (B,) in s and, per term, the uniaxial ``E`` and shear ``G`` moduli (B,) in
    Pa (0 where the term does not act), with the equilibrium ``E_inf``, ``G_inf``."""

    E_inf: float
    G_inf: float
    theta: np.ndarray
    E: np.ndarray
    G: np.ndarray


@dataclass(frozen=True)
class GeneralizedMaxwell:
    """Generalized Maxwell (Prony series) material (see the module docstring); SI units."""

    density: float = 1000.0
    youngs_modulus: float = 1.0e6
    poisson_ratio: float = 0.3
    branches: tuple[Branch, ...] = ()
    density_end: float | None = None
    model: str = "generalized_maxwell"

    def __post_init__(self) -> None:
        C.positive("material.density", self.density)
        C.nonnegative("material.youngs_modulus", self.youngs_modulus)
        C.number("material.poisson_ratio", self.poisson_ratio, low=-1.0, high=0.5,
                 low_incl=False, high_incl=False, allowed="-1 < nu < 1/2 (the equilibrium "
                 "bulk modulus must be finite)")
        if self.density_end is not None:
            C.positive("material.density_end", self.density_end)
        if not self.branches:
            raise ParameterError("material.branches", [], "at least one branch "
                                 "[[material.branches]] (without: model = \"kelvin_voigt\")")
        if self.youngs_modulus > 0.0:        # the branches: the glassy modulus's bound
            check_wave_speed(self.youngs_modulus, self.density, "material.youngs_modulus",
                             "material.density")
        if self.youngs_modulus == 0.0 and not any(b.shear_modulus > 0 for b in self.branches):
            raise ParameterError("material.youngs_modulus", 0.0, "> 0, or a branch with "
                                 "shear stiffness (the rod would have no stiffness)")
        if len(self.branches) > 12:
            raise ParameterError("material.branches", len(self.branches),
                                 "at most 12 branches (24 rod-level relaxation terms)")

    # the Kelvin-Voigt attributes other parts of kvrod read
    tau_S = tau_B = 0.0
    damping = "consistent"
    youngs_modulus_end = None

    @property
    def moduli(self) -> tuple[float, float, np.ndarray, np.ndarray, np.ndarray]:
        """(G_inf, K_inf, G_j, K_j, tau_j) of the 3-D solid (Pa, s)."""
        c = _constitutive()
        E, nu = self.youngs_modulus, self.poisson_ratio
        # E_inf = 0 (a Maxwell fluid's equilibrium) has G = K = 0; the generated moduli
        # take E > 0 only
        G_inf, K_inf = ((0.0, 0.0) if E == 0.0 else
                        (float(c.shear_modulus(E, nu)), float(c.bulk_modulus(E, nu))))
        return (G_inf, K_inf,
                np.array([b.shear_modulus for b in self.branches]),
                np.array([b.bulk_modulus for b in self.branches]),
                np.array([b.tau for b in self.branches]))

    def rod_relaxation(self) -> RodRelaxation:
        """The rod's Prony series on the union of the extension and shear times."""
        pr = _constitutive().maxwell_rod_prony(*self.moduli)
        E_k, th_E = pr["extension"]
        G_k, th_G = pr["shear"]
        theta = sorted_union(th_E, th_G)
        E = np.zeros(theta.size)
        G = np.zeros(theta.size)
        E[np.searchsorted(theta, th_E)] = E_k
        G[np.searchsorted(theta, th_G)] = G_k
        return RodRelaxation(float(pr["E_inf"]), float(pr["G_inf"]), theta, E, G)

    def complex_moduli(self, omega: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """(E*(i omega), G*(i omega)) (Pa): the uniaxial and shear complex moduli."""
        G, _, E = _constitutive().maxwell_moduli_laplace(1j * np.asarray(omega, dtype=float),
                                                         *self.moduli)
        return E, G

    @property
    def tau_E(self) -> float:
        """Low-frequency equivalent retardation time of extension in s, sum_k E_k theta_k
        / E_inf (the Kelvin-Voigt limit; inf without an equilibrium spring)."""
        r = self.rod_relaxation()
        eta = float(np.sum(r.E * r.theta))
        return eta / r.E_inf if r.E_inf > 0 else math.inf

    def describe(self) -> str:
        """One line for reports: the branches and the low-frequency equivalent tau_E."""
        times = ", ".join(f"{b.tau:.4g}" for b in self.branches)
        return (f"generalized Maxwell, {len(self.branches)} branches (tau = {times} s; "
                f"low-frequency tau_E = {self.tau_E:.6g} s)")

    def at(self, x: np.ndarray) -> np.ndarray:
        """Density at the fractions ``x`` of the length."""
        x = np.asarray(x, dtype=float)
        rho_b = self.density if self.density_end is None else self.density_end
        return self.density + (rho_b - self.density) * x

    def rod_matrices(self, section: Section, x: np.ndarray) -> dict[str, np.ndarray]:
        """As :meth:`KelvinVoigt.rod_matrices`, with C_F, C_M the instantaneous
        stiffnesses (equilibrium plus every term), V_F = V_M = 0, and the terms:
        ``theta`` (B,), ``segb`` (n, B, 3), ``jntb`` (n, B, 3) (N and N m^2)."""
        _refuse_composite(section)
        if isinstance(section, GivenStiffness):
            raise ParameterError("section.kind", "stiffness", "a shape (rectangle, ellipse, "
                                 "circle, tube) for a generalized_maxwell material: its "
                                 "moduli scale the section's constants")
        x = np.atleast_1d(np.asarray(x, dtype=float))
        k = section.constants(self.poisson_ratio, x)
        r = self.rod_relaxation()
        A, I1, I2, I3 = k["A"], k["I1"], k["I2"], k["I3"]
        kA1, kA2, kI3 = k["kappa_1"] * A, k["kappa_2"] * A, k["kappa_3"] * I3

        def seg(E, G):
            return np.stack([np.multiply.outer(kA1, G), np.multiply.outer(kA2, G),
                             np.multiply.outer(A, E)], axis=-1)

        def jnt(E, G):
            return np.stack([np.multiply.outer(I1, E), np.multiply.outer(I2, E),
                             np.multiply.outer(kI3, G)], axis=-1)

        segb, jntb = seg(r.E, r.G), jnt(r.E, r.G)               # (n, B, 3)
        CF = seg(np.array([r.E_inf]), np.array([r.G_inf]))[:, 0] + segb.sum(axis=1)
        CM = jnt(np.array([r.E_inf]), np.array([r.G_inf]))[:, 0] + jntb.sum(axis=1)
        rho = self.at(x)
        return {"C_F": CF, "C_M": CM, "V_F": np.zeros_like(CF), "V_M": np.zeros_like(CM),
                "rhoA": rho * A,
                "rhoI": rho[:, None] * np.column_stack([I1, I2, I3]),
                "theta": r.theta, "segb": segb, "jntb": jntb}

    def to_mapping(self) -> dict[str, Any]:
        out: dict[str, Any] = {"model": "generalized_maxwell", "density": self.density,
                               "youngs_modulus": self.youngs_modulus,
                               "poisson_ratio": self.poisson_ratio,
                               "branches": [b.to_mapping() for b in self.branches]}
        if self.density_end is not None:
            out["density_end"] = self.density_end
        return out


Material = KelvinVoigt | GeneralizedMaxwell
MODELS = ("kelvin_voigt", "generalized_maxwell")
_GM_KEYS = ("model", "density", "youngs_modulus", "poisson_ratio", "branches", "density_end")
#: shortest relaxation time of a Maxwell branch (s)
BRANCH_TAU_MIN = 1e-12
_BRANCH_KEYS = ("tau", "youngs_modulus", "poisson_ratio", "shear_modulus", "bulk_modulus")


def _branch_from_mapping(path: str, m: Any) -> Branch:
    m = C.table(path, m)
    C.no_unknown_keys(path, m, _BRANCH_KEYS)
    C.exclusive(path, m, ("youngs_modulus", "poisson_ratio"),
                ("shear_modulus", "bulk_modulus"))
    if "tau" not in m:
        raise ParameterError(f"{path}.tau", None, "a relaxation time in s (> 0)")
    tau = C.number(f"{path}.tau", m["tau"], low=BRANCH_TAU_MIN,
                   allowed=f"a relaxation time >= {BRANCH_TAU_MIN:g} s (a faster branch acts "
                   "on no time scale a rod simulation resolves: the energy audit fails from "
                   "1e-14 s and the consistent start from 1e-16 s)")
    if "shear_modulus" in m or "bulk_modulus" in m:
        G = C.nonnegative(f"{path}.shear_modulus", m.get("shear_modulus", 0.0))
        K = C.nonnegative(f"{path}.bulk_modulus", m.get("bulk_modulus", 0.0))
    else:
        if "youngs_modulus" not in m or "poisson_ratio" not in m:
            raise ParameterError(f"{path}.youngs_modulus", m.get("youngs_modulus"),
                                 "youngs_modulus and poisson_ratio, or shear_modulus and "
                                 "bulk_modulus (Pa)")
        E = C.nonnegative(f"{path}.youngs_modulus", m["youngs_modulus"])
        nu = C.number(f"{path}.poisson_ratio", m["poisson_ratio"], low=-1.0, high=0.5,
                      low_incl=False, high_incl=False, allowed="-1 < nu < 1/2")
        Gj, Kj = _constitutive().maxwell_branch_moduli(E, nu)
        G, K = float(Gj), float(Kj)
    if G == 0.0 and K == 0.0:
        raise ParameterError(f"{path}.shear_modulus", 0.0, "a branch with stiffness (> 0)")
    return Branch(G, K, tau)
_KV_KEYS = ("model", "density", "youngs_modulus", "poisson_ratio", "tau", "tau_S", "tau_B",
            "eta", "zeta", "damping", "density_end", "youngs_modulus_end")


def material_from_mapping(m: Mapping[str, Any] | None) -> Material:
    """A material from a ``[material]`` table (see the module docstring).

    Parameters
    ----------
    m : mapping or None
        The table; ``model`` selects ``kelvin_voigt`` (default) or
        ``generalized_maxwell``; None gives the default Kelvin-Voigt material.

    Returns
    -------
    KelvinVoigt or GeneralizedMaxwell

    Raises
    ------
    ParameterError
        A key is unknown or a value outside its range (the message names it).
    """
    m = dict(C.table("material", m if m is not None else {}))
    model = C.choice("material.model", m.get("model", "kelvin_voigt"), MODELS)
    if model == "generalized_maxwell":
        C.no_unknown_keys("material", m, _GM_KEYS)
        br = m.get("branches", [])
        if not isinstance(br, list):
            raise ParameterError("material.branches", br, "an array of tables "
                                 "[[material.branches]]")
        kw = {key: C.number(f"material.{key}", m[key]) for key in
              ("density", "youngs_modulus", "poisson_ratio", "density_end") if key in m}
        return GeneralizedMaxwell(branches=tuple(
            _branch_from_mapping(f"material.branches[{i}]", b) for i, b in enumerate(br)),
            **kw)
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
    segments inside, the end segment's value at the ends (the clamp joints). Used for the
    relaxation terms of generalized Maxwell rods (uniform along the rod but for tapers);
    the Kelvin-Voigt stiffness and viscosity take :func:`joint_series`."""
    a = np.asarray(per_segment, dtype=float)
    out = np.empty((a.shape[0] + 1,) + a.shape[1:])
    out[0], out[-1] = a[0], a[-1]
    out[1:-1] = 0.5 * (a[:-1] + a[1:])
    return out


def joint_series(stiffness: np.ndarray, viscosity: np.ndarray,
                 h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint stiffness and viscosity (N+1, 3) from the segments' diagonals (N, 3) of
    lengths h (N,) (m): the two half cells of a joint's cell in series.

    A joint's cell reaches half a segment into each neighbour (h_j = (h_i + h_i+1)/2);
    its compliance is that of the two halves in series,
    ``h_j / C_j = (h_i/2) / C_i + (h_i+1/2) / C_i+1``, which is what the continuum's
    moment-curvature integral over the cell gives where C jumps at the node: a sharp change
    of section or material stays second order in h (the arithmetic mean made it first
    order: docs/design.md, section 10). The viscosity follows from the series combination
    of the two Kelvin-Voigt half cells at low frequency (their compliances
    ``1/(C + s V)`` added and expanded to first order in s):
    ``h_j V_j / C_j^2 = (h_i/2) V_i / C_i^2 + (h_i+1/2) V_i+1 / C_i+1^2``, so a common
    retardation time stays that time (V = tau C gives V_j = tau C_j) and a damped half
    beside an undamped one damps the joint. Equal neighbours give their own values
    exactly; the ends (clamp joints) the end segment's."""
    C = np.asarray(stiffness, dtype=float)
    V = np.asarray(viscosity, dtype=float)
    h = np.asarray(h, dtype=float).reshape(-1)
    Cj = np.empty((C.shape[0] + 1,) + C.shape[1:])
    Vj = np.empty_like(Cj)
    Cj[0], Cj[-1], Vj[0], Vj[-1] = C[0], C[-1], V[0], V[-1]
    if C.shape[0] > 1:
        wa, wb = 0.5 * h[:-1, None], 0.5 * h[1:, None]
        Ca, Cb, Va, Vb = C[:-1], C[1:], V[:-1], V[1:]
        with np.errstate(divide="ignore", invalid="ignore"):
            c = (wa + wb) / (wa / Ca + wb / Cb)
            v = c * c * (wa * Va / (Ca * Ca) + wb * Vb / (Cb * Cb)) / (wa + wb)
        same_c = Ca == Cb
        Cj[1:-1] = np.where(same_c, Ca, c)
        Vj[1:-1] = np.where(same_c & (Va == Vb), Va, v)
    return Cj, Vj
