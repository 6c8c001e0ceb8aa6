"""The cross-section analysis: 6x6 stiffness, consistent and naive viscosity, inertia.

:func:`analyse_section` meshes the regions, solves the finite-element problem of
:mod:`runtime.section.fe`, refines the mesh until every diagonal entry of the stiffness and
of both viscosities changes by less than ``tol`` (relative) from one mesh to the next, and
returns the result about the elastic centroid (tension centre).

Conventions (kvrod's kernels, ``derive/steps/kinematics.py``): rod strains
(Gamma1, Gamma2, Gamma3, K1, K2, K3): shears along d1, d2, extension, bending about d1 (axial
strain x2 K1), bending about d2 (axial strain -x1 K2), torsion; resultants
(T1, T2, T3, M1, M2, M3) with M1 = <x2 sigma33>, M2 = <-x1 sigma33>. A homogeneous
isotropic section has K = diag(kappa1 G A, kappa2 G A, E A, E I1, E I2, G J_T) with
I1 = <x2^2>, the shear factors being the energy-consistent ones of Saint-Venant flexure.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from shapely.ops import unary_union

from runtime.errors import ParameterError
from runtime.section import fe
from runtime.section.materials import SectionMaterial, as_material_map
from runtime.section.mesh import Mesh, mesh_regions
from runtime.section.regions import Region, check_regions, regions_from_mapping
from runtime.signals import check_cancelled, run_interruptibly

#: strain and resultant names, in the order of the 6x6 matrices
STRAINS = ("Gamma1", "Gamma2", "Gamma3", "K1", "K2", "K3")
RESULTANTS = ("T1", "T2", "T3", "M1", "M2", "M3")
DEFAULT_TOL = 1e-4
MAX_LEVELS = 8
MAX_NODES = 120_000


@dataclass(frozen=True)
class SectionResult:
    """Cross-section properties about the elastic centroid (SI units).

    ``stiffness`` K (6x6; N, N m, N m^2 blocks), ``viscosity`` (consistent, 6x6, the same
    units times s), ``viscosity_naive`` (traction route, not symmetric in general), in
    strain order (Gamma1, Gamma2, Gamma3, K1, K2, K3) and resultant order (T1, T2, T3, M1, M2,
    M3); ``reference_point`` = ``elastic_centroid`` (x1, x2) [m]; ``shear_centre`` [m];
    ``mass_per_length`` [kg/m], ``mass_centre`` [m], ``rotary_inertia`` about the mass
    centre [kg m]: I11 = <rho (x2 - c2)^2> (about d1), I22 = <rho (x1 - c1)^2> (about d2),
    I12 = <rho (x1 - c1)(x2 - c2)> (product), polar = I11 + I22; ``area`` [m^2].
    ``compliance`` F = K^-1 about the elastic centroid; ``torsional_stiffness`` G J_T =
    1/F[5, 5] [N m^2], the torque per twist without shear forces (independent of the
    reference point; K[5, 5] about a point other than the shear centre is larger, by the
    shear strain that twisting about that point implies).
    Convergence: ``mesh_size`` h [m] of the final mesh, ``n_elements``, ``n_nodes``,
    ``tolerance``, ``achieved_change`` (largest relative change of a diagonal entry from
    the previous mesh), ``converged``, ``history`` (h, change) per mesh; ``warnings``.
    ``info``: what a caller adds (the problem layer: the damping route, the regions, the
    closed-form rod model), merged into :meth:`to_dict`.
    """

    stiffness: np.ndarray
    viscosity: np.ndarray
    viscosity_naive: np.ndarray
    compliance: np.ndarray
    torsional_stiffness: float
    elastic_centroid: tuple[float, float]
    shear_centre: tuple[float, float]
    mass_per_length: float
    mass_centre: tuple[float, float]
    rotary_inertia: dict[str, float]
    area: float
    mesh_size: float
    n_elements: int
    n_nodes: int
    tolerance: float
    achieved_change: float
    converged: bool
    history: tuple[tuple[float, float], ...]
    warnings: tuple[str, ...] = ()
    mesh: Mesh | None = field(default=None, repr=False, compare=False)
    info: Mapping[str, Any] = field(default_factory=dict, repr=False, compare=False)

    @property
    def reference_point(self) -> tuple[float, float]:
        return self.elastic_centroid

    def _line_of_action(self, V: np.ndarray) -> tuple[float, float] | None:
        if not V[2, 2] > 0.0:
            return None
        c1, c2 = self.elastic_centroid
        return (c1 - float(V[4, 2]) / float(V[2, 2]), c2 + float(V[3, 2]) / float(V[2, 2]))

    @property
    def viscous_centroid(self) -> tuple[float, float] | None:
        """Where the viscous axial force of a uniform extension rate acts [m] (consistent
        viscosity): the elastic centroid + (-V[4, 2], V[3, 2]) / V[2, 2], with M1 =
        <x2 sigma33>, M2 = <-x1 sigma33> about the centroid. Off the elastic centroid
        when the viscosity is distributed otherwise than the stiffness (a composite of
        polymers and metals); None for an elastic section (V[2, 2] = 0)."""
        return self._line_of_action(self.viscosity)

    @property
    def viscous_centroid_naive(self) -> tuple[float, float] | None:
        """As :attr:`viscous_centroid` for the naive (traction) viscosity [m]."""
        return self._line_of_action(self.viscosity_naive)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping (the keys of ``kvrod section``'s section.json)."""
        return {
            "stiffness": self.stiffness.tolist(),
            "viscosity": self.viscosity.tolist(),
            "viscosity_naive": self.viscosity_naive.tolist(),
            "torsional_stiffness": self.torsional_stiffness,
            "strain_order": list(STRAINS),
            "mass_per_length": self.mass_per_length,
            "mass_centre": list(self.mass_centre),
            "rotary_inertia": dict(self.rotary_inertia),
            "elastic_centroid": list(self.elastic_centroid),
            "shear_centre": list(self.shear_centre),
            "reference_point": list(self.reference_point),
            "viscous_centroid": (None if self.viscous_centroid is None
                                 else list(self.viscous_centroid)),
            "viscous_centroid_naive": (None if self.viscous_centroid_naive is None
                                       else list(self.viscous_centroid_naive)),
            "area": self.area,
            "mesh": {"size": self.mesh_size, "elements": self.n_elements,
                     "nodes": self.n_nodes, "tolerance": self.tolerance,
                     "achieved_change": _finite(self.achieved_change),
                     "converged": self.converged,
                     "history": [[h, _finite(c)] for h, c in self.history]},
            "warnings": list(self.warnings),
            **{k: v for k, v in self.info.items()},
        }


def _finite(x: float) -> float | None:
    """JSON has no infinity: the first mesh's change (no previous mesh) is None."""
    return x if math.isfinite(x) else None


def shift(c: tuple[float, float]) -> np.ndarray:
    """P with theta_origin = P theta_c for resultants given at the point c (m):
    M_origin = M_c + c x T."""
    P = np.eye(6)
    c1, c2 = c
    P[3, 2], P[4, 2] = c2, -c1
    P[5, 0], P[5, 1] = -c2, c1
    return P


def _scale_vector(L: float) -> np.ndarray:
    return np.array([L, L, L, L * L, L * L, L * L])


@dataclass
class _Level:
    h: float
    mesh: Mesh
    F: np.ndarray       # compliance about the reference origin, SI units
    Fc: np.ndarray      # compliance about the elastic centroid
    K: np.ndarray
    V: np.ndarray
    Vn: np.ndarray
    centroid: tuple[float, float]
    shear_centre: tuple[float, float]


def _element_materials(mesh: Mesh, mats: Sequence[SectionMaterial], c0: float, v0: float
                       ) -> tuple[fe.ElementMaterial, fe.ElementMaterial]:
    r = mesh.region
    C = np.stack([m.stiffness - m.bulk_excess * np.outer(fe.M_VOL, fe.M_VOL) for m in mats])
    V = np.stack([m.viscosity - m.bulk_viscosity_excess * np.outer(fe.M_VOL, fe.M_VOL)
                  for m in mats])
    kx = np.array([m.bulk_excess for m in mats])
    vx = np.array([m.bulk_viscosity_excess for m in mats])
    return (fe.ElementMaterial(C[r] / c0, kx[r] / c0), fe.ElementMaterial(V[r] / v0, vx[r] / v0))


def _solve_level(regions: Sequence[Region], mats: Sequence[SectionMaterial], h: float,
                 factors: Sequence[float], origin: np.ndarray, L: float, c0: float,
                 v0: float) -> _Level:
    return _solve_mesh(mesh_regions(regions, h, factors), mats, origin, L, c0, v0)


def _solve_mesh(mesh: Mesh, mats: Sequence[SectionMaterial], origin: np.ndarray, L: float,
                c0: float, v0: float) -> _Level:
    """The analysis on one mesh (region i of material mats[i]), solved in coordinates
    (x - origin) / L with the stiffness over c0 and the viscosity over v0; SI results."""
    h = mesh.h
    scaled = Mesh(nodes=(mesh.nodes - origin) / L, elements=mesh.elements,
                  region=mesh.region, h=h / L)
    stiff, visc = _element_materials(mesh, mats, c0, v0)
    sol = fe.solve(scaled, stiff, visc)
    s = _scale_vector(L)
    # back to SI about the origin: forces scale with c0 s_i, strains with 1/s_j
    F = sol.F / (c0 * np.outer(s, s))
    FV = sol.FV * v0 / (c0 * c0 * np.outer(s, s))
    NV = sol.NV * v0 / c0 * np.outer(s, 1.0 / s)
    # elastic centroid: an axial force there gives no curvature (F about the origin)
    a = np.array([[-F[3, 4], F[3, 3]], [-F[4, 4], F[4, 3]]])
    ce = np.linalg.solve(a, -F[3:5, 2])
    sc = np.array([-F[5, 1] / F[5, 5], F[5, 0] / F[5, 5]])
    P = shift((float(ce[0]), float(ce[1])))
    Pinv = np.linalg.inv(P)
    Fc = P.T @ F @ P
    Fc = 0.5 * (Fc + Fc.T)
    Kc = np.linalg.inv(Fc)
    Kc = 0.5 * (Kc + Kc.T)
    Ko = np.linalg.inv(F)
    Vo = Ko @ FV @ Ko
    Vno = NV @ Ko
    Vc = Pinv @ Vo @ Pinv.T
    Vnc = Pinv @ Vno @ Pinv.T
    return _Level(h=h, mesh=mesh, F=F, Fc=Fc, K=Kc, V=0.5 * (Vc + Vc.T), Vn=Vnc,
                  centroid=(float(ce[0] + origin[0]), float(ce[1] + origin[1])),
                  shear_centre=(float(sc[0] + origin[0]), float(sc[1] + origin[1])))


def _change(new: _Level, old: _Level) -> float:
    worst = 0.0
    for a, b in ((new.K, old.K), (new.V, old.V), (new.Vn, old.Vn)):
        da, db = np.diag(a), np.diag(b)
        scale = np.maximum(np.abs(da), 1e-300)
        if not np.any(da):
            continue
        mask = np.abs(da) > 1e-12 * np.max(np.abs(da))
        worst = max(worst, float(np.max(np.abs(da - db)[mask] / scale[mask])))
    return worst


def _mass(mesh: Mesh, mats: Sequence[SectionMaterial]) -> dict[str, Any]:
    g = fe.geometry(mesh.nodes, mesh.elements)
    rho = np.array([m.density for m in mats])[mesh.region]
    wr = g.w * rho[:, None]
    m = float(wr.sum())
    c = (wr[..., None] * g.x).sum(axis=(0, 1)) / m
    d = g.x - c
    I11 = float((wr * d[..., 1] ** 2).sum())
    I22 = float((wr * d[..., 0] ** 2).sum())
    I12 = float((wr * d[..., 0] * d[..., 1]).sum())
    return {"mass": m, "centre": (float(c[0]), float(c[1])), "area": float(g.w.sum()),
            "inertia": {"I11": I11, "I22": I22, "I12": I12, "polar": I11 + I22}}


def _check_first_mesh(regions: Sequence[Region], polys: Sequence[Any], h: float,
                      factors: Sequence[float]) -> None:
    """Refuse a section whose first mesh would already exceed MAX_NODES (a region so thin
    against the section that its elements, about 1.5 times its thickness, number in the
    millions: a 20 mm strip with a ply 1e-9 m wide took all the memory and was killed)."""
    # six-node triangles: about two nodes per element; equilateral elements of edge h_i
    per_region = [2.0 * p.area / (hi * hi * math.sqrt(3.0) / 4.0)
                  for p, hi in zip(polys, (h * f for f in factors), strict=True)]
    if sum(per_region) <= MAX_NODES:
        return
    i = int(np.argmax(per_region))
    p = polys[i]
    name = regions[i].name or f"section.regions[{i}]"
    raise ParameterError(
        f"section.regions[{i}].shape", regions[i].shape.kind,
        f"a region not too thin against the section: {name!r} is about "
        f"{2.0 * p.area / p.length:.3g} m thick (2 area / perimeter) and its elements of "
        f"about that size would need ~{per_region[i]:.2g} mesh nodes, more than the "
        f"{MAX_NODES} the analysis allows; make it thicker or leave it out")


def analyse_section(regions: Sequence[Region] | Any,
                    materials: Mapping[str, SectionMaterial] | Any, *,
                    tol: float = DEFAULT_TOL, h: float | None = None,
                    max_levels: int = MAX_LEVELS) -> SectionResult:
    """Stiffness, consistent and naive viscosity and inertia of a composite section.

    Parameters
    ----------
    regions
        :class:`~runtime.section.regions.Region` objects, or the ``[[section.regions]]``
        array of tables.
    materials
        {name: :class:`~runtime.section.materials.SectionMaterial`}, or the
        ``[materials]`` table.
    tol
        Relative change of every diagonal entry of K, V and V_naive between two successive
        meshes below which the refinement stops (default 1e-4).
    h
        Edge length of the first mesh [m] (default: sqrt(area) / 8); a region thinner than
        h / 1.5 takes elements of 1.5 times its thickness (2 area / perimeter).
    max_levels
        At most this many meshes (each with h / sqrt(2)).

    Returns
    -------
    SectionResult
        About the elastic centroid; not converged (with a warning) when ``max_levels``
        meshes or the node limit did not reach ``tol``.

    Raises
    ------
    ParameterError
        Bad regions or materials (overlaps, unknown material names, bad values), or a
        mesh the mesher cannot make within its budget
        (:class:`~runtime.section.mesh.MeshBudgetError`).

    Notes
    -----
    Called from the main thread, the analysis runs in a worker thread
    (:func:`runtime.signals.run_interruptibly`): Ctrl-C and SIGTERM stop it within a
    fraction of a second, also during a factorization of many seconds.
    """
    return run_interruptibly(_analyse, regions, materials, tol=tol, h=h,
                             max_levels=max_levels)


def _analyse(regions: Sequence[Region] | Any, materials: Mapping[str, SectionMaterial] | Any,
             *, tol: float, h: float | None, max_levels: int) -> SectionResult:
    """:func:`analyse_section` in the calling thread."""
    if not (isinstance(tol, (int, float)) and 1e-9 <= tol <= 0.1):
        raise ParameterError("tol", tol, "a relative tolerance, 1e-9 ... 0.1")
    mats_map = as_material_map(materials)
    if not (isinstance(regions, Sequence) and regions
            and all(isinstance(r, Region) for r in regions)):
        regions = regions_from_mapping(regions)
    check_regions(regions, mats_map)
    used = [mats_map[r.material] for r in regions]
    total = sum(r.shape.area for r in regions)
    polys = [r.shape.polygon(math.sqrt(total) / 16) for r in regions]
    origin = np.array(unary_union(polys).centroid.coords[0])
    L = math.sqrt(total)
    c0 = max(float(np.max(np.abs(m.stiffness))) for m in used)
    v0 = max([float(np.max(np.abs(m.viscosity))) for m in used] + [c0 * 1e-300, 1e-300])
    if h is not None and not (isinstance(h, (int, float)) and 0 < h < math.inf):
        raise ParameterError("h", h, "a mesh size in m (> 0)")
    # ~ thickness of each region (2 A / perimeter): thin regions get smaller elements
    thin = [2.0 * p.area / p.length for p in polys]
    if h is None:
        h = L / 8.0
    factors = [min(1.0, 1.5 * t / h) for t in thin]
    _check_first_mesh(regions, polys, h, factors)
    levels: list[_Level] = []
    history: list[tuple[float, float]] = []
    warnings = [w for m in used for w in m.warnings]
    change = math.inf
    hk = float(h)
    for _ in range(max_levels):
        check_cancelled()                  # the caller was interrupted: stop here
        lev = _solve_level(regions, used, hk, factors, origin, L, c0, v0)
        if levels:
            change = _change(lev, levels[-1])
        history.append((hk, change))
        levels.append(lev)
        if change < tol or 2 * lev.mesh.nodes.shape[0] > MAX_NODES:
            break                          # converged, or the next mesh would be too large
        hk /= math.sqrt(2.0)
    best = levels[-1]
    converged = change < tol
    if not converged:
        warnings.append(f"mesh refinement stopped at h = {best.h:.4g} m with a relative "
                        f"change of {change:.3g} (> tol = {tol:g}); the result is less "
                        "accurate than asked")
    mass = _mass(best.mesh, used)
    return SectionResult(
        stiffness=best.K, viscosity=best.V, viscosity_naive=best.Vn, compliance=best.Fc,
        torsional_stiffness=float(1.0 / best.Fc[5, 5]),
        elastic_centroid=best.centroid, shear_centre=best.shear_centre,
        mass_per_length=mass["mass"], mass_centre=mass["centre"],
        rotary_inertia=mass["inertia"], area=mass["area"], mesh_size=best.h,
        n_elements=int(best.mesh.elements.shape[0]), n_nodes=int(best.mesh.nodes.shape[0]),
        tolerance=float(tol), achieved_change=float(change), converged=converged,
        history=tuple(history), warnings=tuple(warnings), mesh=best.mesh)
