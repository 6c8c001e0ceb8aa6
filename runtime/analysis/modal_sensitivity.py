"""Derivatives of a rod's damped modes with respect to problem parameters (issue 34):
d omega / d theta and d zeta / d theta of the modes of
:func:`~runtime.analysis.modal.modal_analysis`.

Eigenvalue derivatives
----------------------
A damped eigenvalue ``lambda`` of the first-order pencil ``(A + lambda E) x = 0``
(``Linearization``) with its left eigenvector ``u``
(``u^H (A + lambda E) = 0``) moves with a parameter as

    d lambda = - u^H (dA + lambda dE) x / (u^H E x)

(simple eigenvalue; the same formula for the undamped ``(K - omega^2 M) phi = 0`` with
``A = K``, ``E = -M``, ``lambda = omega^2``). A cluster of k coincident eigenvalues (the
two bending families of a circular or square section) is treated as one: with bases
``X``, ``U`` of its right and left invariant subspaces the derivatives are the
eigenvalues of ``-(U^H E X)^-1 U^H (dA + lambda dE) X`` (k x k), each given to the
mode of the cluster whose shape its eigenvector resembles most. The eigenvectors are
computed here by (block) inverse iteration on the sparse pencil at the modes'
eigenvalues (one complex LU per eigenvalue cluster).

``dA``, ``dE`` (and ``dK``, ``dM``)
-----------------------------------
The derivatives of the linearisation's matrices along the parameter: central
differences of ``linearize`` of the problem at
``theta +- h`` (mesh fixed, ``h`` = 1e-4 of the value), linearised about ``y_eq +- h
dy_eq/dtheta`` (the static sensitivities, ``runtime.model.static_sensitivity``, for a
deformed analysis; the perturbed problem's reference otherwise). Where the matrices are
linear in the parameter (moduli, densities, retardation times, about the reference) the
difference is exact to round-off; elsewhere its error is O(h^2) (1e-8 relative).

What is differentiated
----------------------
``omega``: the undamped natural frequency of a Kelvin-Voigt rod (``Mode.omega``), the
modulus ``|lambda|`` = ``sqrt(lambda_1 lambda_2)`` of a generalized Maxwell rod's pair;
``zeta = -(lambda_1 + lambda_2) / (2 sqrt(lambda_1 lambda_2))`` of the damped pair
(an overdamped mode's two real eigenvalues each by its own derivative). A rigid mode
(omega 0, no damping ratio) has derivatives 0 and NaN.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from runtime.analysis.modal import Linearization, Mode, linearize
from runtime.problem.parameters import ResolvedParameter, array_directions, with_parameters

#: relative step of the linearisation's difference
STEP = 1e-4
#: eigenvalues within this relative distance form one cluster
CLUSTER_RTOL = 1e-6


def analysed_problem(problem, deformed: bool):
    """The problem a modal analysis linearises: as given about its static state
    (``deformed``), else without its loads about the reference (``kvrod modes``' rule)."""
    return problem if deformed else replace(problem, loads=())


def _linearisation(problem, deformed: bool, y_eq: np.ndarray | None) -> Linearization:
    from runtime.problem.assemble import build_model

    model = build_model(analysed_problem(problem, deformed))
    return linearize(model, y_eq, equilibrium_rtol=1e-3)


def matrix_derivatives(problem, r: ResolvedParameter, deformed: bool,
                       y_eq: np.ndarray | None, dy_eq: np.ndarray | None
                       ) -> dict[str, sp.csc_matrix]:
    """dA, dE, dK, dM of the linearisation along parameter ``r`` (central differences at
    theta +- h about y_eq +- h dy_eq; see the module docstring)."""
    h = STEP * (abs(r.value) if r.value != 0.0 else 1.0)
    lins = []
    for sign in (1.0, -1.0):
        p = with_parameters(problem, {r.name: r.value + sign * h})
        y = None if y_eq is None else y_eq + sign * h * dy_eq
        lins.append(_linearisation(p, deformed, y))
    plus, minus = lins
    return {k: ((getattr(plus, k) - getattr(minus, k)) / (2 * h)).tocsc()
            for k in ("A", "E", "K", "M")}


def _subspaces(A, E, lam: complex, k: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """Right and left bases (n, k) of the eigenvalue cluster at ``lam`` of ``A + lam E``
    (block inverse iteration, shift a relative 1e-10 off the eigenvalue)."""
    n = A.shape[0]
    shift = lam + 1e-10 * max(abs(lam), 1.0) * (1.0 + 1.0j)
    lu = spla.splu((A + shift * E).astype(complex).tocsc())
    X = rng.standard_normal((n, k)) + 0j
    U = rng.standard_normal((n, k)) + 0j
    for _ in range(3):
        X = np.linalg.qr(lu.solve(X))[0]
        U = np.linalg.qr(lu.solve(U, trans="H"))[0]
    return X, U


def cluster_derivatives(A, E, dA, dE, lam: complex, k: int, rng
                        ) -> tuple[np.ndarray, np.ndarray]:
    """The derivatives (k,) of a cluster of k eigenvalues at ``lam`` of ``A + lam E``
    along (dA, dE), and the right eigenvectors (n, k) they belong to."""
    X, U = _subspaces(A, E, lam, k, rng)
    G = U.conj().T @ (E @ X)
    H = -(U.conj().T @ ((dA + lam * dE) @ X))
    d, c = np.linalg.eig(np.linalg.solve(G, H))
    return d, X @ c


def _clusters(values: Sequence[complex]) -> list[list[int]]:
    out: list[list[int]] = []
    for i, v in enumerate(values):
        for group in out:
            w = values[group[0]]
            if abs(v - w) <= CLUSTER_RTOL * max(abs(w), 1e-300):
                group.append(i)
                break
        else:
            out.append([i])
    return out


def _assign(d: np.ndarray, vecs: np.ndarray, shapes: list[np.ndarray], W) -> list[complex]:
    """Give the k derivatives of a cluster to its k modes: each mode the derivative whose
    eigenvector's W-weighted overlap with its shape is largest (greedy)."""
    k = d.size
    if k == 1:
        return [complex(d[0])]
    n = shapes[0].size
    ov = np.abs(np.array([[np.vdot(s, W @ vecs[:n, j]) for j in range(k)] for s in shapes]))
    ov /= np.maximum(np.linalg.norm(vecs[:n], axis=0)[None, :], 1e-300)
    out: list[complex] = [0j] * k
    free = list(range(k))
    for i in np.argsort(-ov.max(axis=1)):
        j = max(free, key=lambda j: ov[i, j])
        free.remove(j)
        out[i] = complex(d[j])
    return out


def _mode_vector(lin: Linearization, m: Mode) -> np.ndarray:
    """A mode's undamped shape in the reduced unknowns (nq,)."""
    dx = np.zeros(lin.statics.n_static)
    dx[lin.statics.phi_cols] = m.displacement.T
    dx[lin.statics.theta_cols] = m.rotation.T
    return dx[lin.dofs]


def _zeta_derivative(l1: complex, l2: complex, d1: complex, d2: complex
                     ) -> tuple[float, float]:
    """(d wn, d zeta) of a pair from its eigenvalues' derivatives: wn = sqrt(l1 l2),
    zeta = -(l1 + l2) / (2 wn)."""
    wn = np.sqrt(l1 * l2)
    dwn = (d1 * l2 + l1 * d2) / (2 * wn)
    dz = -(d1 + d2) / (2 * wn) + (l1 + l2) / (2 * wn * wn) * dwn
    return float(np.real(dwn)), float(np.real(dz))


def mode_derivatives(lin: Linearization, modes: Sequence[Mode], mats: dict,
                     seed: int = 0) -> dict[str, np.ndarray]:
    """d omega and d zeta (len(modes),) of the modes of ``lin`` along the matrices'
    derivatives ``mats`` (``matrix_derivatives``)."""
    rng = np.random.default_rng(seed)
    maxwell = lin.model.branches > 0
    k = len(modes)
    d_omega, d_zeta = np.zeros(k), np.full(k, math.nan)
    live = [i for i, m in enumerate(modes) if m.omega > 0]     # not the unresisted rigid
    shapes = {i: _mode_vector(lin, modes[i]) for i in live}
    # the damped pair: lambda_1 of each mode (lambda_2 its conjugate, or its own real one)
    eig: list[tuple[int, int, complex]] = []
    for i in live:
        l1, l2 = modes[i].eigenvalues
        eig.append((i, 0, complex(l1)))
        if abs(l1.imag) == 0.0 and math.isfinite(l2.real):
            eig.append((i, 1, complex(l2)))
    dl: dict[tuple[int, int], complex] = {}
    W = lin.M
    for group in _clusters([v for _, _, v in eig]):
        lam = eig[group[0]][2]
        d, vecs = cluster_derivatives(lin.A, lin.E, mats["A"], mats["E"], lam, len(group),
                                      rng)
        got = _assign(d, vecs, [shapes[eig[g][0]] for g in group], W)
        for g, v in zip(group, got, strict=True):
            dl[eig[g][:2]] = v
    if not maxwell:              # the undamped frequencies: (K - omega^2 M) phi = 0
        w2 = [modes[i].omega ** 2 for i in live]
        for group in _clusters(w2):
            idx = [live[g] for g in group]
            d, vecs = cluster_derivatives(lin.K, -lin.M, mats["K"], -mats["M"],
                                          complex(w2[group[0]]), len(group), rng)
            got = _assign(d, vecs, [shapes[i] for i in idx], W)
            for i, v in zip(idx, got, strict=True):
                d_omega[i] = float(np.real(v)) / (2 * modes[i].omega)
    for i in live:
        l1, l2 = modes[i].eigenvalues
        d1 = dl.get((i, 0))
        if abs(l1.imag) > 0.0:
            d2 = np.conj(d1)
        elif (i, 1) in dl:
            d2 = dl[(i, 1)]
        else:
            continue
        dwn, dz = _zeta_derivative(complex(l1), complex(l2), d1, d2)
        if math.isfinite(modes[i].zeta):
            d_zeta[i] = dz
        if maxwell:
            d_omega[i] = dwn
    return {"omega": d_omega, "zeta": d_zeta}


def modal_sensitivities(problem, resolved: Sequence[ResolvedParameter], modes: Sequence[Mode],
                        model, y_eq: np.ndarray | None, deformed: bool
                        ) -> dict[str, dict[str, np.ndarray]]:
    """``{name: {"omega": (k,), "zeta": (k,)}}`` (rad/s and 1 per unit of the parameter)
    of ``modes``, the modes of ``model`` (the build of ``analysed_problem``) about
    ``y_eq`` (the static state of a ``deformed`` analysis, else None), for the
    parameters ``resolved`` of ``problem`` (the problem as given, loads included)."""
    from runtime.model.static_sensitivity import static_sensitivities

    lin = linearize(model, y_eq)
    dys: list[np.ndarray | None] = [None] * len(resolved)
    if deformed and y_eq is not None:
        dirs, _ = array_directions(problem, resolved, model.arrays)
        model.set_directions(dirs)
        try:
            with model.statics():
                S = static_sensitivities(model, y_eq)
        finally:
            model.set_directions(None)
        dys = list(S)
    out: dict[str, dict[str, np.ndarray]] = {}
    for r, dy in zip(resolved, dys, strict=True):
        mats = matrix_derivatives(problem, r, deformed, y_eq, dy)
        out[r.name] = mode_derivatives(lin, modes, mats)
    return out
