"""Finite-element cross-section analysis on one mesh (Giavotto et al. 1983; BECAS).

Displacement of the prismatic solid: a rigid-section motion plus a warping g(x1, x2; x3)
(three components, six-node isoparametric triangles). With the rod strains
psi = (Gamma1, Gamma2, Gamma3, K1, K2, K3) the 3-D strain (Voigt 11, 22, 33, 23, 13, 12,
engineering shears) is

    eps = Z(x) psi + B g + S dg/dx3,

Z the rigid-section strain field (kvrod's kinematics, paper (17): eps33 = Gamma3 + x2 K1
- x1 K2, gamma13 = Gamma1 - x2 K3, gamma23 = Gamma2 + x1 K3), B the in-plane derivatives
(eps11 = g1,1, eps22 = g2,2, gamma23 = g3,2, gamma13 = g3,1, gamma12 = g1,2 + g2,1) and S the
axial ones (eps33 = g3', gamma23 = g2', gamma13 = g1'). With the section matrices

    E = <(BN)^T C BN>, Cm = <(SN)^T C BN>, M = <(SN)^T C SN>,
    R = <(BN)^T C Z>,  L = <(SN)^T C Z>,   A = <Z^T C Z>,

the Saint-Venant solutions for stress resultants theta = (T1, T2, T3, M1, M2, M3) that vary
linearly along the rod, theta' = Q theta (rod equilibrium T' = 0, M' + d3 x T = 0), are
g = X theta, psi = Y theta with (BECAS's two systems; D^T g = 0 removes the six rigid
modes of the warping and makes the split unique; here D picks six pinned dofs, see _pins)

    [E R D; R^T A 0; D^T 0 0] [dX; dY; .] = [0; Q; 0],                       dX = X Q
    [E R D; R^T A 0; D^T 0 0] [X; Y; .]   = [(Cm - Cm^T) dX + L dY; I - L^T dX; 0].

The strain of a unit resultant is W_theta = B N X + S N dX + Z Y, the compliance
F = <W_theta^T C W_theta> (energy per length 1/2 theta^T F theta) and the stiffness K = F^-1.
The map from rod strains to the section's elastic strain field is W = W_theta K; the
consistent viscosity is <W^T V W> = K <W_theta^T V W_theta> K and the naive (traction)
one <Z^T V W> = <Z^T V W_theta> K.

Nearly incompressible isotropic regions: the bulk modulus above 10 G (and the same share of
the bulk viscosity) acts on the element mean of the volumetric strain (a mixed u-p
formulation with piecewise constant pressure, condensed per element; P2-P0 is inf-sup
stable, so such regions do not lock), in every matrix above alike.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from runtime.section.cholesky import cholesky
from runtime.section.element import shape_functions
from runtime.section.materials import M_VOL
from runtime.section.mesh import Mesh

# Dunavant's 7-point rule, degree 5 (area coordinates; weights sum to 1)
_A1, _B1, _W1 = 0.059715871789770, 0.470142064105115, 0.132394152788506
_A2, _B2, _W2 = 0.797426985353087, 0.101286507323456, 0.125939180544827
QUAD_L = np.array([[1 / 3, 1 / 3, 1 / 3],
                   [_A1, _B1, _B1], [_B1, _A1, _B1], [_B1, _B1, _A1],
                   [_A2, _B2, _B2], [_B2, _A2, _B2], [_B2, _B2, _A2]])
QUAD_W = 0.5 * np.array([0.225, _W1, _W1, _W1, _W2, _W2, _W2])   # reference area 1/2

#: rod equilibrium theta' = Q theta: M1' = T2, M2' = -T1 (M' + d3 x T = 0)
Q_EQ = np.zeros((6, 6))
Q_EQ[3, 1] = 1.0
Q_EQ[4, 0] = -1.0


#: the operators as sums of products: strain i of unknown (a, j) at a point is
#: sum_c phi[a, c] D[i, j, c]. B: phi = dN_a/dx_c, j the warping component (eps11 = g1,1,
#: eps22 = g2,2, gamma23 = g3,2, gamma13 = g3,1, gamma12 = g1,2 + g2,1)
D_B = np.zeros((6, 3, 2))
D_B[0, 0, 0] = D_B[1, 1, 1] = D_B[3, 2, 1] = D_B[4, 2, 0] = D_B[5, 0, 1] = D_B[5, 1, 0] = 1.0
#: S: phi = N_a (one c), eps33 = g3', gamma23 = g2', gamma13 = g1'
D_S = np.zeros((6, 3, 1))
D_S[2, 2, 0] = D_S[3, 1, 0] = D_S[4, 0, 0] = 1.0
#: Z: phi = (1, x1, x2) (one "node"), j the rod strain: eps33 = Gamma3 + x2 K1 - x1 K2,
#: gamma23 = Gamma2 + x1 K3, gamma13 = Gamma1 - x2 K3
D_Z = np.zeros((6, 6, 3))
D_Z[2, 2, 0] = D_Z[3, 1, 0] = D_Z[4, 0, 0] = 1.0
D_Z[2, 3, 2], D_Z[2, 4, 1] = 1.0, -1.0
D_Z[3, 5, 1], D_Z[4, 5, 2] = 1.0, -1.0


def _rigid_basis(x: np.ndarray) -> np.ndarray:
    """(1, x1, x2) at points x (..., 2): (..., 3)."""
    return np.concatenate([np.ones(x.shape[:-1] + (1,)), x], axis=-1)


def rigid_strain(x: np.ndarray) -> np.ndarray:
    """Z at points x (..., 2): (..., 6, 6), rows Voigt strain, columns rod strains."""
    return np.einsum("...m,ijm->...ij", _rigid_basis(x), D_Z)


@dataclass
class Operator:
    """A strain operator on an element's unknowns, as a sum of products: at point q of
    element e, strain i of unknown (a, j) is sum_c phi[e, q, a, c] D[i, j, c] (a a node,
    j a component, c a derivative or basis function); unknowns node-major, a * nj + j."""

    phi: np.ndarray          # (ne, nq, na, nc)
    D: np.ndarray            # (6, nj, nc)

    def at_points(self) -> np.ndarray:
        """The operator at every point: (ne, nq, 6, na * nj)."""
        ne, nq = self.phi.shape[:2]
        return np.einsum("eqac,ijc->eqiaj", self.phi, self.D).reshape(ne, nq, 6, -1)

    def apply(self, u: np.ndarray) -> np.ndarray:
        """P u at every point for element values u (ne, na * nj, k): (ne, nq, 6, k)."""
        ne, nq, na, nc = self.phi.shape
        nj, k = self.D.shape[1], u.shape[-1]
        phiT = self.phi.transpose(0, 1, 3, 2).reshape(ne, nq * nc, na)
        grad = np.matmul(phiT, u.reshape(ne, na, nj * k)).reshape(ne * nq, nc * nj, k)
        # one product with the selectors for all points: (6, nc nj) @ (nc nj, ne nq k)
        cols = grad.transpose(1, 0, 2).reshape(nc * nj, ne * nq * k)
        out = self.D.transpose(0, 2, 1).reshape(6, nc * nj) @ cols
        return out.reshape(6, ne, nq, k).transpose(1, 2, 0, 3)


@dataclass
class Geometry:
    """Per element and quadrature point: weights w (ne, nq) [m^2], points x (ne, nq, 2),
    N (nq, 6), dN/dx (ne, nq, 6, 2); element areas (ne,)."""

    w: np.ndarray
    x: np.ndarray
    N: np.ndarray
    dN: np.ndarray
    area: np.ndarray


def geometry(nodes: np.ndarray, elements: np.ndarray) -> Geometry:
    N, dNr = shape_functions(QUAD_L)
    xe = nodes[elements]                                   # (ne, 6, 2)
    J = np.matmul(xe.transpose(0, 2, 1)[:, None], dNr)     # J[c, b] = dx_c / dxi_b
    det = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    if np.any(det <= 0):
        raise RuntimeError("the section mesh has an inverted element")
    inv = np.empty_like(J)
    inv[..., 0, 0], inv[..., 1, 1] = J[..., 1, 1] / det, J[..., 0, 0] / det
    inv[..., 0, 1], inv[..., 1, 0] = -J[..., 0, 1] / det, -J[..., 1, 0] / det
    dN = np.matmul(dNr, inv)                               # dN_a / dx_c
    w = QUAD_W[None, :] * det
    x = np.matmul(N, xe)
    return Geometry(w=w, x=x, N=N, dN=dN, area=w.sum(axis=1))


def strain_operators(g: Geometry) -> tuple[Operator, Operator, Operator]:
    """B N and S N (18 unknowns: (g1, g2, g3) per node) and Z (the 6 rod strains)."""
    ne, nq = g.w.shape
    B = Operator(phi=g.dN, D=D_B)
    S = Operator(phi=np.broadcast_to(g.N[None, :, :, None], (ne, nq, 6, 1)), D=D_S)
    Z = Operator(phi=_rigid_basis(g.x)[:, :, None, :], D=D_Z)
    return B, S, Z


@dataclass
class ElementMaterial:
    """Per element: the regular part of a Voigt matrix (ne, 6, 6) and the excess bulk part
    (ne,) taken on the element-mean volumetric strain."""

    regular: np.ndarray
    excess: np.ndarray

    def form(self, g: Geometry, P: Operator | np.ndarray, R: Operator | np.ndarray
             ) -> np.ndarray:
        """Element matrices <P^T M R> (ne, p, r) for operators P and R: two
        :class:`Operator` (the point sum taken on their basis functions, then the material
        on their selectors), or either at the points, (ne, nq, 6, p)."""
        if isinstance(P, Operator) and isinstance(R, Operator):
            out = self._form_operators(g, P, R)
        else:
            out = self._form_points(g, _points(P), _points(R))
        if np.any(self.excess):
            mp, mr = _volumetric_mean(g, P), _volumetric_mean(g, R)
            out += (self.excess / g.area)[:, None, None] * mp[:, :, None] * mr[:, None, :]
        return out

    def _form_points(self, g: Geometry, P: np.ndarray, R: np.ndarray) -> np.ndarray:
        # per element: the material on all points' strains at once, then the point sum
        ne, nq = g.w.shape
        Rt = R.transpose(0, 2, 1, 3).reshape(ne, 6, -1)                # (ne, 6, nq r)
        MR = np.matmul(self.regular, Rt).reshape(ne, 6 * nq, -1)
        wP = (g.w[:, None, :, None] * P.transpose(0, 2, 1, 3)).reshape(ne, 6 * nq, -1)
        return np.matmul(wP.transpose(0, 2, 1), MR)

    def _form_operators(self, g: Geometry, P: Operator, R: Operator) -> np.ndarray:
        # <P^T M R>[(a, j), (b, l)] = sum_cd H[a, c, b, d] K[j, c, l, d] with
        # H = sum_q w phiP[a, c] phiR[b, d] and K = D_P[:, j, c]^T M D_R[:, l, d]
        ne, nq, na, nc = P.phi.shape
        nb, nd = R.phi.shape[2:]
        nj, nl = P.D.shape[1], R.D.shape[1]
        wp = (g.w[:, :, None, None] * P.phi).reshape(ne, nq, na * nc)
        H = np.matmul(wp.transpose(0, 2, 1), R.phi.reshape(ne, nq, nb * nd))
        H = H.reshape(ne, na, nc, nb, nd).transpose(0, 1, 3, 2, 4).reshape(ne, na * nb, nc * nd)
        K = P.D.reshape(6, nj * nc).T @ self.regular @ R.D.reshape(6, nl * nd)
        K = K.reshape(ne, nj, nc, nl, nd).transpose(0, 2, 4, 1, 3).reshape(ne, nc * nd, nj * nl)
        out = np.matmul(H, K).reshape(ne, na, nb, nj, nl).transpose(0, 1, 3, 2, 4)
        return out.reshape(ne, na * nj, nb * nl)


def _points(P: Operator | np.ndarray) -> np.ndarray:
    return P.at_points() if isinstance(P, Operator) else P


def _volumetric_mean(g: Geometry, P: Operator | np.ndarray) -> np.ndarray:
    """<M_VOL . P> per element: (ne, p)."""
    if isinstance(P, Operator):
        ne, nq, na, nc = P.phi.shape
        v = np.tensordot(M_VOL, P.D, axes=(0, 0))                  # (nj, nc)
        wphi = np.einsum("eq,eqac->eac", g.w, P.phi)
        return np.matmul(wphi, v.T).reshape(ne, -1)
    return np.einsum("eq,eqp->ep", g.w, np.matmul(M_VOL, P))


@dataclass
class Solution:
    """Scaled solution on one mesh: compliance F, viscous forms about the mesh origin."""

    F: np.ndarray           # <W_theta^T C W_theta>
    FV: np.ndarray          # <W_theta^T V W_theta>
    NV: np.ndarray          # <Z^T V W_theta>
    n_dofs: int


def _pins(x: np.ndarray) -> np.ndarray:
    """Six warping dofs held at zero: (g1, g2, g3) at a node a, at the node b farthest from
    a the in-plane component across a-b and g3, and g3 at the node c farthest from the line
    a-b. They remove the six rigid modes of the warping (three translations, the in-plane
    rotation and the two tilts g3 = x2, g3 = -x1 that trade with the shear strains), as
    BECAS's constraint D^T g = 0 does; the strain field, and so every result, does not
    depend on which constraint is chosen (their multipliers vanish at the solution: the
    loads of both systems are self-equilibrated), and pins keep the matrix sparse."""
    a = int(np.argmin(np.hypot(*(x - x.mean(axis=0)).T)))
    b = int(np.argmax(np.hypot(*(x - x[a]).T)))
    d = (x[b] - x[a]) / np.linalg.norm(x[b] - x[a])
    c = int(np.argmax(np.abs((x[:, 0] - x[a, 0]) * d[1] - (x[:, 1] - x[a, 1]) * d[0])))
    across = 1 if abs(d[0]) >= abs(d[1]) else 0
    return np.array(sorted({3 * a, 3 * a + 1, 3 * a + 2, 3 * b + across, 3 * b + 2,
                            3 * c + 2}))


def solve(mesh: Mesh, stiff: ElementMaterial, visc: ElementMaterial) -> Solution:
    """The Giavotto/BECAS solution on ``mesh`` (coordinates, C and V already scaled).

    E is factored once (after pinning: symmetric positive definite, the sparse Cholesky
    of :mod:`runtime.section.cholesky`); the six columns of R and the load of the second
    system are its only right-hand sides (the first system's warping load is zero)."""
    g = geometry(mesh.nodes, mesh.elements)
    B, S, Z = strain_operators(g)
    ne = mesh.elements.shape[0]
    n = 3 * mesh.nodes.shape[0]
    dofs = (3 * mesh.elements[:, :, None] + np.arange(3)[None, None, :]).reshape(ne, 18)

    def gather(u: np.ndarray) -> np.ndarray:
        """Element values (ne, 18, k) of a global field u (n, k)."""
        return u[dofs]

    def scatter(ue: np.ndarray) -> np.ndarray:
        """The global field (n, k) assembled from element contributions (ne, 18, k)."""
        k = ue.shape[-1]
        flat = (dofs[:, :, None] * k + np.arange(k)).ravel()
        return np.bincount(flat, weights=ue.ravel(), minlength=n * k).reshape(n, k)

    pins = _pins(mesh.nodes)
    pinned = np.zeros(n, dtype=bool)
    pinned[pins] = True
    free = np.flatnonzero(~pinned)            # (setdiff1d sorts all n: 30 ms at n = 125k)
    index = np.full(n, -1)
    index[free] = np.arange(free.size)
    rows = np.repeat(index[dofs], 18, axis=1).ravel()
    cols = np.tile(index[dofs], (1, 18)).ravel()
    held = (rows >= 0) & (cols >= 0)
    Ee = stiff.form(g, B, B).ravel()[held]
    E = sp.coo_matrix((Ee, (rows[held], cols[held])), shape=(free.size, free.size))
    factor = cholesky(E, free // 3)
    Cm = stiff.form(g, S, B)
    R = scatter(stiff.form(g, B, Z))
    L = scatter(stiff.form(g, S, Z))
    A = stiff.form(g, Z, Z).sum(axis=0)
    Rf = R[free]
    ER = factor.solve(Rf)
    schur = A - Rf.T @ ER

    def bordered(a: np.ndarray | None, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """[E R; R^T A] [u; y] = [a; b] with the pinned dofs of u zero (a = None: 0)."""
        ea = np.zeros((free.size, 6)) if a is None else factor.solve(a[free])
        y = np.linalg.solve(schur, b - Rf.T @ ea)
        u = np.zeros((n, 6))
        u[free] = ea - ER @ y
        return u, y

    dX, dY = bordered(None, Q_EQ)
    dXe = gather(dX)
    CmdX = scatter(np.matmul(Cm, dXe) - np.matmul(Cm.transpose(0, 2, 1), dXe))  # (Cm - Cm^T) dX
    X, Y = bordered(CmdX + L @ dY, np.eye(6) - L.T @ dX)
    # strain of unit resultants at every point: W_theta (ne, nq, 6, 6)
    Zp = Z.at_points()
    W = B.apply(gather(X)) + S.apply(dXe) + Zp @ Y
    F = stiff.form(g, W, W).sum(axis=0)
    FV = visc.form(g, W, W).sum(axis=0)
    NV = visc.form(g, Zp, W).sum(axis=0)
    return Solution(F=0.5 * (F + F.T), FV=0.5 * (FV + FV.T), NV=NV, n_dofs=n)
