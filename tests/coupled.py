"""Rods with coupled sections for the tests: random symmetric positive definite 6x6
stiffness and positive semi-definite viscosity about the centreline, a mass centre off
the centreline and a product of inertia (held-out sections: no test names a matrix)."""

from __future__ import annotations

import numpy as np

from runtime.model.arrays import coupled_arrays
from runtime.model.rod import RodModel
from tests.rods import rod_model


def random_section(rng, diag: np.ndarray, coupling: float = 0.5) -> np.ndarray:
    """S C S with S = diag(sqrt(diag)) and C = (1 - c) I + c G, G a random Gram matrix of
    unit vectors (symmetric positive definite, unit diagonal, off-diagonal entries below
    ``c = coupling``)."""
    B = rng.standard_normal((6, 6))
    G = B @ B.T
    d = np.sqrt(np.diag(G))
    C = (1.0 - coupling) * np.eye(6) + coupling * G / np.outer(d, d)
    s = np.sqrt(np.asarray(diag, dtype=float))
    return C * np.outer(s, s)


def coupled_model(rng, N: int = 6, start: str = "clamped", end: str = "free",
                  loads: bool | list = True, offset: bool = True, tau: float = 0.04,
                  varying: bool = False, **kw) -> RodModel:
    """The test rod of :func:`tests.rods.rod_model` with a random coupled section (the
    same on every segment unless ``varying``), viscosity ``tau`` times another random
    coupled matrix, a mass centre off the centreline and a product of inertia."""
    m = rod_model(N, start, end, loads=loads, **kw)
    a = m.arrays
    diag = np.r_[a.seg_field("C_F")[0], a.jnt_field("C_M")[1 if N > 1 else 0]]
    K0, V0 = random_section(rng, diag), tau * random_section(rng, diag)
    scale = rng.uniform(0.7, 1.4, N) if varying else np.ones(N)
    K = scale[:, None, None] * K0
    V = scale[:, None, None] * V0
    rhoI = a.seg_field("rhoI")[0]
    J = np.diag(rhoI)
    J[0, 1] = J[1, 0] = -0.3 * np.sqrt(rhoI[0] * rhoI[1])
    e = np.array([1.5e-3, -1e-3]) if offset else np.zeros(2)
    ac = coupled_arrays(a, K, V, np.tile(J, (N, 1, 1)), np.tile(e, (N, 1)))
    return RodModel(ac, m.reference, drive=m.drive)
