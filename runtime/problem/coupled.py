"""Coupled sections in a problem (issue 26; docs/design.md, section 10): the rod matrices
of a ``stiffness`` section given by its 6x6 matrices and of a composite section (from its
finite-element analysis, cached per distinct section), in the form the model's arrays
take (:func:`runtime.model.arrays.coupled_arrays`).

A coupled section's rod matrices are the dict of
:meth:`runtime.problem.materials.KelvinVoigt.rod_matrices` (the diagonals ``C_F``,
``C_M``, ``V_F``, ``V_M``, ``rhoA``, ``rhoI``, which the checks and reports read) plus
``K6``, ``V6`` (n, 6, 6) about the centreline, ``rhoJ`` (n, 3, 3), rho times the section's
inertia about its mass centre per length, and ``mass_centre`` (n, 2) in the material
frame.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np

from runtime.errors import ParameterError

#: the mesh tolerance of the section analysis a composite rod is simulated with
COMPOSITE_TOL = 1e-4
#: a naive viscosity whose antisymmetric part stays below this (of the geometric mean of
#: the diagonals) is symmetric to the mesh's accuracy and taken as its symmetric part
NAIVE_SYMMETRY_TOL = 1e-6
#: what a non-symmetric viscosity is refused with
NONSYMMETRIC = (
    "'consistent' for this section: its naive (traction-route) viscosity is not "
    "symmetric (|V_ij - V_ji| / sqrt(V_ii V_jj) up to {asym:.3g} at [{i}][{j}]); a "
    "non-symmetric viscosity has no dissipation function, and the rod's viscous forces are "
    "derived from one (its antisymmetric part would do no work: a gyroscopic force, not "
    "damping). `kvrod section` reports both routes")


def inertia_matrix(rhoI1: float, rhoI2: float, rhoI3: float, rhoI12: float) -> np.ndarray:
    """rho times the rotary inertia tensor per length in the material frame (kg m):
    ``((I11, -I12, 0), (-I12, I22, 0), (0, 0, I33))`` with I11 = <rho x2^2>, I22 =
    <rho x1^2>, I12 = <rho x1 x2> (the kinetic energy 1/2 Omega^T J Omega of a section
    spinning about its mass centre)."""
    return np.array([[rhoI1, -rhoI12, 0.0], [-rhoI12, rhoI2, 0.0], [0.0, 0.0, rhoI3]])


def coupled_dict(K: np.ndarray, V: np.ndarray, rhoA: float, J: np.ndarray,
                 e: np.ndarray, n: int) -> dict[str, np.ndarray]:
    """The rod matrices of a uniform coupled section at n points (see the module
    docstring)."""
    K, V, J = (np.asarray(a, dtype=float) for a in (K, V, J))
    tile = lambda a: np.tile(a, (n,) + (1,) * np.ndim(a))  # noqa: E731
    dK, dV = np.diag(K), np.diag(V)
    return {"C_F": tile(dK[:3]), "C_M": tile(dK[3:]), "V_F": tile(dV[:3]),
            "V_M": tile(dV[3:]), "rhoA": np.full(n, float(rhoA)), "rhoI": tile(np.diag(J)),
            "K6": tile(K), "V6": tile(V), "rhoJ": tile(J),
            "mass_centre": tile(np.asarray(e, dtype=float))}


def given_matrices(section: Any, tau: np.ndarray, n: int) -> dict[str, np.ndarray]:
    """A ``stiffness`` section with couplings: its matrices, the viscosity given or
    ``V_ij = sqrt(t_i t_j) K_ij`` from the material's retardation times
    ``t = (tau_S, tau_S, tau_E, tau_E, tau_E, tau_S)`` (symmetric positive semi-definite,
    and ``diag(t) K`` for a diagonal K: the diagonal stiffness section's rule)."""
    K = section.matrix()
    if section.viscosity_matrix is not None:
        V = np.array(section.viscosity_matrix)
    else:
        s = np.sqrt(np.asarray(tau, dtype=float))
        V = K * np.outer(s, s)
    from runtime.problem.sections import check_section_matrix

    check_section_matrix("section.viscosity_matrix", V, False,
                         "N s (Gamma, Gamma), N m s (Gamma, K), N m^2 s (K, K)")
    J = inertia_matrix(section.rhoI1, section.rhoI2, section.rhoI3, section.rhoI12)
    return coupled_dict(K, V, section.rhoA, J, np.array(section.mass_centre), n)


@lru_cache(maxsize=32)
def _analysis(key: str, section: Any) -> Any:
    from runtime.section import analyse_section

    return analyse_section(section.regions, section.used_materials(), tol=COMPOSITE_TOL)


def composite_analysis(section: Any) -> Any:
    """The finite-element analysis of a composite section (``runtime.section``), once per
    distinct section in a process (a sweep's points share it)."""
    return _analysis(section._key(), section)


def composite_matrices(section: Any, n: int) -> dict[str, np.ndarray]:
    """A composite section's rod matrices: its stiffness and viscosity (the consistent
    one, or the naive one when it is symmetric to the mesh's accuracy, by
    ``section.damping``) about the elastic centroid, which is the rod's centreline; the
    mass centre relative to it; the rotary inertia about the mass centre."""
    res = composite_analysis(section)
    K = 0.5 * (res.stiffness + res.stiffness.T)
    V = np.array(res.viscosity if section.damping == "consistent" else res.viscosity_naive)
    d = np.sqrt(np.abs(np.outer(np.diag(V), np.diag(V))))
    asym = np.abs(V - V.T) / np.where(d > 0, d, 1.0)
    if section.damping == "naive" and np.max(asym) > NAIVE_SYMMETRY_TOL:
        i, j = np.unravel_index(int(np.argmax(asym)), V.shape)
        raise ParameterError("section.damping", "naive",
                             NONSYMMETRIC.format(asym=float(np.max(asym)), i=i, j=j))
    V = 0.5 * (V + V.T)
    ri = res.rotary_inertia
    J = inertia_matrix(ri["I11"], ri["I22"], ri["polar"], ri["I12"])
    e = np.array(res.mass_centre) - np.array(res.elastic_centroid)
    return coupled_dict(K, V, res.mass_per_length, J, e, n)
