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
import scipy.sparse.linalg as spla

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


def rigid_strain(x: np.ndarray) -> np.ndarray:
    """Z at points x (..., 2): (..., 6, 6), rows Voigt strain, columns rod strains."""
    Z = np.zeros(x.shape[:-1] + (6, 6))
    x1, x2 = x[..., 0], x[..., 1]
    Z[..., 2, 2] = 1.0
    Z[..., 2, 3] = x2
    Z[..., 2, 4] = -x1
    Z[..., 3, 1] = 1.0
    Z[..., 3, 5] = x1
    Z[..., 4, 0] = 1.0
    Z[..., 4, 5] = -x2
    return Z


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
    J = np.einsum("qab,eac->eqcb", dNr, xe)                # J[c, b] = dx_c / dxi_b
    det = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    if np.any(det <= 0):
        raise RuntimeError("the section mesh has an inverted element")
    inv = np.empty_like(J)
    inv[..., 0, 0], inv[..., 1, 1] = J[..., 1, 1] / det, J[..., 0, 0] / det
    inv[..., 0, 1], inv[..., 1, 0] = -J[..., 0, 1] / det, -J[..., 1, 0] / det
    dN = np.einsum("qab,eqbc->eqac", dNr, inv)             # dN_a / dx_c
    w = QUAD_W[None, :] * det
    x = np.einsum("qa,eac->eqc", N, xe)
    return Geometry(w=w, x=x, N=N, dN=dN, area=w.sum(axis=1))


def strain_operators(g: Geometry) -> tuple[np.ndarray, np.ndarray]:
    """B N and S N per element and point: (ne, nq, 6, 18), dofs (g1, g2, g3) per node."""
    ne, nq = g.w.shape
    B = np.zeros((ne, nq, 6, 18))
    S = np.zeros((ne, nq, 6, 18))
    d1, d2 = g.dN[..., 0], g.dN[..., 1]
    B[:, :, 0, 0::3] = d1
    B[:, :, 1, 1::3] = d2
    B[:, :, 3, 2::3] = d2
    B[:, :, 4, 2::3] = d1
    B[:, :, 5, 0::3] = d2
    B[:, :, 5, 1::3] = d1
    Nb = np.broadcast_to(g.N, (ne, nq, 6))
    S[:, :, 2, 2::3] = Nb
    S[:, :, 3, 1::3] = Nb
    S[:, :, 4, 0::3] = Nb
    return B, S


@dataclass
class ElementMaterial:
    """Per element: the regular part of a Voigt matrix (ne, 6, 6) and the excess bulk part
    (ne,) taken on the element-mean volumetric strain."""

    regular: np.ndarray
    excess: np.ndarray

    def form(self, g: Geometry, P: np.ndarray, R: np.ndarray) -> np.ndarray:
        """Element matrices <P^T M R> (ne, p, r) for operators P (ne, nq, 6, p) and
        R (ne, nq, 6, r)."""
        MR = np.einsum("eij,eqjr->eqir", self.regular, R)
        out = np.einsum("eq,eqip,eqir->epr", g.w, P, MR)
        if np.any(self.excess):
            mp = np.einsum("eq,i,eqip->ep", g.w, M_VOL, P)
            mr = np.einsum("eq,i,eqir->er", g.w, M_VOL, R)
            out += (self.excess / g.area)[:, None, None] * mp[:, :, None] * mr[:, None, :]
        return out


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
    """The Giavotto/BECAS solution on ``mesh`` (coordinates, C and V already scaled)."""
    g = geometry(mesh.nodes, mesh.elements)
    B, S = strain_operators(g)
    Z = rigid_strain(g.x)
    ne = mesh.elements.shape[0]
    n = 3 * mesh.nodes.shape[0]
    dofs = (3 * mesh.elements[:, :, None] + np.arange(3)[None, None, :]).reshape(ne, 18)
    rows = np.repeat(dofs, 18, axis=1).ravel()
    cols = np.tile(dofs, (1, 18)).ravel()

    def square(Pe: np.ndarray) -> sp.csr_matrix:
        return sp.csr_matrix((Pe.ravel(), (rows, cols)), shape=(n, n))

    def rect(Pe: np.ndarray) -> np.ndarray:
        out = np.zeros((n, 6))
        np.add.at(out, dofs.ravel(), Pe.reshape(-1, 6))
        return out

    E = square(stiff.form(g, B, B))
    Cm = square(stiff.form(g, S, B))
    R = rect(stiff.form(g, B, Z))
    L = rect(stiff.form(g, S, Z))
    A = stiff.form(g, Z, Z).sum(axis=0)
    pins = _pins(mesh.nodes)
    free = np.setdiff1d(np.arange(n), pins)
    Ef = E[free][:, free].tocsc()
    lu = spla.splu(Ef, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                   options={"SymmetricMode": True})
    ER = lu.solve(R[free])
    schur = A - R[free].T @ ER

    def bordered(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """[E R; R^T A] [u; y] = [a; b] with the pinned dofs of u zero."""
        ea = lu.solve(a[free])
        y = np.linalg.solve(schur, b - R[free].T @ ea)
        u = np.zeros((n, a.shape[1]))
        u[free] = ea - ER @ y
        return u, y

    dX, dY = bordered(np.zeros((n, 6)), Q_EQ)
    X, Y = bordered((Cm - Cm.T) @ dX + L @ dY, np.eye(6) - L.T @ dX)
    # strain of unit resultants at every point: W_theta (ne, nq, 6, 6)
    Xe, dXe = X[dofs], dX[dofs]                                  # (ne, 18, 6)
    W = (np.einsum("eqip,epk->eqik", B, Xe) + np.einsum("eqip,epk->eqik", S, dXe)
         + np.einsum("eqij,jk->eqik", Z, Y))
    F = stiff.form(g, W, W).sum(axis=0)
    FV = visc.form(g, W, W).sum(axis=0)
    NV = visc.form(g, Z, W).sum(axis=0)
    return Solution(F=0.5 * (F + F.T), FV=0.5 * (FV + FV.T), NV=NV, n_dofs=n)
