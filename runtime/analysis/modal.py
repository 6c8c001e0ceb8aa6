"""Damped modal analysis of the discrete Kelvin-Voigt rod about a static equilibrium.

Linearisation
-------------
The rod's IDA residual ``F(t, y, y') = 0`` (``runtime/model/rod.py``) is linearised at an
equilibrium ``y_eq`` at rest (the straight reference or a pre-deformed static state from
``runtime.solvers.statics.solve_static``, loads kept on). The quaternions carry one redundant
coordinate each (their norm, which the strains ignore), so the linearisation is written in
reduced coordinates, in the layout of the static problem (``generated/rod_layout.py``):

* positions ``q``: node displacements ``dphi_i`` (m) and segment rotation increments
  ``dtheta_j`` (rad, material, ``p <- p * exp(dtheta/2)``), mapped to ``dy = T q`` with
  ``dp = G(p) dtheta``, ``G(p) = 1/2 L(p)[:, 1:]`` (the map of ``RodModel.static_retract``);
* velocities ``w``: node velocities ``v_i`` (m/s) and material angular velocities
  ``Omega_j`` (rad/s), which are state components already (``dy = S w``).

Fixed nodes (clamped or pinned ends) are removed. The momentum rows of the residual (rows
of ``v`` at free nodes, of ``Omega`` on segments) give

    M w' + C w + K q = 0,   M = dF/dy'[mom] S,  C = dF/dy[mom] S,  K = dF/dy[mom] T,

and the kinematic rows (``phi' - v`` and the quaternion row ``p' - 1/2 p*(0, Omega)``, the
latter projected with ``4 G(p)^T``, so ``4 G^T G = I``) give ``q' - w = 0``; both are read
from the generated Jacobians ``dF_dy_sparse`` / ``dF_dyp_sparse``. The first-order pencil
``E x' + A x = 0`` with ``x = (q, w)`` gives the damped eigenvalues ``lambda`` from
``-A x = lambda E x``; the undamped natural frequencies come from ``K phi = omega^2 M phi``.

Per mode
--------
natural (undamped) angular frequency ``omega`` (rad/s), the damped eigenvalue pair
``(lambda_1, lambda_2)`` (a complex-conjugate pair for an underdamped mode, two negative
reals for an overdamped one; 1/s), the damping ratio ``zeta = -(lambda_1 + lambda_2) /
(2 sqrt(lambda_1 lambda_2))`` (``= -Re(lambda)/|lambda|`` for a complex pair, > 1 when
overdamped), the mode shape (node displacements and segment rotations; its sign fixed, see
below) and the family from the fractions of the mode's strain energy in the six strain
components
``V1, V2`` (shear), ``V3`` (extension), ``U1, U2`` (bending about d1, d2), ``U3`` (torsion).
Kelvin-Voigt damping with ``V = diag(tau) C`` (eq. (9)) gives ``zeta = omega tau / 2`` per
family: ``tau_E`` for bending and extension, ``tau_S`` for torsion and shear.

Rigid modes
-----------
The rigid motions the supports leave free (:func:`runtime.model.rigid.rigid_motions`: the
spin of a pinned-pinned rod about the line through its pins, the six motions of a
free-free rod, the rotations of a pinned-free rod about its pin) are computed from the
geometry of ``y_eq``. Those the linearised stiffness does not resist (``K z = 0`` and
``z^T K = 0`` to round-off; all of them in an unloaded state) are taken out of the
eigenproblem exactly: the elastic modes are solved on the M-orthogonal complement (dense:
projected onto it; sparse: shift-invert through the bordered matrix
``[[K, M Z], [Z^T M, 0]]``, regular where K is singular), and the rigid modes are reported
as family ``rigid`` with ``omega = 0``, eigenvalues (0, 0), no damping ratio (``zeta`` and
``zeta_modal`` NaN, ``null`` in JSON) and zero strain energy, listed first. Rigid motions
that the loads do resist (the spin of a sagged pinned-pinned beam, a pendulum in the
gravity field) are ordinary modes of the linearisation; a mode whose M-norm lies mostly
(> 1/2) in the rigid motions is labelled ``rigid`` with its own (pendulum) frequency, or
with omega = 0 and no damping ratio where omega^2 is below the eigensolvers' round-off
(1e-12 of the largest stiffness-to-mass ratio).

Solvers
-------
By default the sparse method of :mod:`runtime.analysis.modal_sparse` at every size
(shift-invert Lanczos for the undamped modes, the modal projection's prediction of the
damped eigenvalues, refined by block shift-invert iteration on the sparse pencil and a
Rayleigh functional step on the second-order problem with the internal strains eliminated
per frequency): N = 4000 Kelvin-Voigt (eight modes) or the Maxwell cantilever at N = 1000
in about 2 s. The ``count`` lowest modes, or with ``target`` the ``count`` nearest a
natural frequency (the rule of ``_select``). Dense LAPACK (``scipy.linalg.eig`` of the whole
pencil, QZ for a Maxwell rod) is the test oracle, used up to ``dense_max`` reduced unknowns
(default 0) and for problems too small for ARPACK.

Degenerate pairs (the two bending families of a circular or square section) are solved
together: one M-orthonormal pair of undamped shapes from Lanczos, rotated to the two
bending families (``_separate_degenerate``), and their damped eigenvalues as Ritz
values of one small projected problem, so the twins' zeta agree to round-off (1e-9 at
N = 4000). They are listed in the order that rotation gives (ascending bending-1 energy:
bending-2 first).

Sign of a mode shape
--------------------
An eigenvector is defined up to its sign, and eigensolvers return either (a rerun, another
BLAS, a degenerate pair rotated differently). Every mode shape, rigid modes included, is
therefore normalised by one rule (:func:`fix_sign`): the component of the reduced mode
vector (node displacements in m, segment rotations in rad, mass-normalised) with the
largest magnitude is positive; where several are within a relative 1e-6 of the largest
(symmetric shapes), the first of them in the state's order decides. So every consumer
(modes.json, the mode-shape plots, the notes) sees the same shape on every run.

Limitation: damped eigenvalues are paired with undamped modes by the participation of the
mode shapes. For strongly overdamped modes whose damping is not proportional (e.g. the
torsion mode of a loaded, bent rod, which mixes with bending) this pairing is not unique;
``Mode.zeta_modal`` (uncoupled modal damping) is then the more meaningful figure.
"""

from __future__ import annotations

import cmath
import math
import warnings
from dataclasses import asdict, dataclass, field

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from runtime.errors import ParameterError
from runtime.model.rod import RodModel
from runtime.model.statics import RodStatics

#: largest first-order system (positions, velocities, internal strains) of a generalized
#: Maxwell rod solved (dense eigenvalues)
MAXWELL_DENSE_MAX = 3000

__all__ = [
    "FAMILIES",
    "STRAIN_COMPONENTS",
    "Linearization",
    "Mode",
    "family_retardation_time",
    "linearize",
    "modal_analysis",
]

#: strain components in the order of the energy fractions
STRAIN_COMPONENTS = ("V1", "V2", "V3", "U1", "U2", "U3")
#: family names ("rigid": a rigid motion the supports leave free)
FAMILIES = ("bending-1", "bending-2", "torsion", "axial", "shear", "rigid")
#: a rigid motion z is "not resisted" when |K z| and |K^T z| are below this fraction of
#: the size of the terms summed (|K| |z|): round-off, not a stiffness
RIGID_NULL_RTOL = 1e-10


# --------------------------------------------------------------------------------------
# Linearisation
# --------------------------------------------------------------------------------------


@dataclass
class Linearization:
    """Linearised rod about ``y_eq`` in reduced coordinates (see module docstring).

    M (kg, kg m^2), C (N s/m, N m s), K (N/m, N m/rad): sparse CSC (nq, nq) on the free
    reduced unknowns ``dofs`` (indices into the static layout of size ``n_static``);
    E, A: first-order pencil (2 nq, 2 nq), ``E x' + A x = 0``, ``x = (q, w)``;
    T (n, n_static): tangent map ``dy = T dx`` of the positions and rotations.
    """

    model: RodModel
    y_eq: np.ndarray
    dofs: np.ndarray
    M: sp.csc_matrix
    C: sp.csc_matrix
    K: sp.csc_matrix
    E: sp.csc_matrix
    A: sp.csc_matrix
    T: sp.csc_matrix
    statics: RodStatics

    @property
    def nq(self) -> int:
        """Number of reduced position unknowns."""
        return int(self.dofs.size)

    def expand(self, q: np.ndarray) -> np.ndarray:
        """Reduced vector (nq,) -> static-layout increment dx (n_static,), zeros at fixed."""
        dx = np.zeros(self.statics.n_static, dtype=np.asarray(q).dtype)
        dx[self.dofs] = q
        return dx


def _check_equilibrium(st: RodStatics, y0: np.ndarray, rtol: float) -> None:
    """ValueError unless the static residual at y0 is small against the loads (or rod forces)."""
    model = st.model
    r = np.empty(st.n_static)
    st.static_residual(y0, r)
    s0 = model.load_scale
    try:
        st.load_scale = 0.0
        r0 = np.empty(st.n_static)
        st.static_residual(y0, r0)
    finally:
        st.load_scale = s0
    load = float(np.max(np.abs(r - r0)))
    # round-off floor of the internal forces: 1e-9 of the largest stiffness (N)
    a = model.arrays
    length = float(np.sum(a.seg_field("h")))
    floor = 1e-9 * max(float(np.max(a.seg_field("C_F"))),
                       float(np.max(a.jnt_field("C_M"))) / length)
    bad = float(np.max(np.abs(r)))
    if bad > rtol * load and bad > floor:
        raise ValueError(f"y_eq is not an equilibrium under the model's loads: static residual "
                         f"{bad:.3g} against the load {load:.3g} (solve_static first)")


def linearize(model: RodModel, y_eq: np.ndarray | None = None,
              equilibrium_rtol: float = 1e-6) -> Linearization:
    """Linearise the rod's residual at the equilibrium ``y_eq`` (default: straight, at rest).

    Velocities of ``y_eq`` are set to zero; the model's loads are those of statics
    (``RodModel.statics``: at t = 0-, times ``load_scale``), so a state from the static
    solve is linearised under its load. Raises ValueError if ``y_eq`` is not an
    equilibrium (max static residual above ``equilibrium_rtol`` times the load scale).
    """
    with model.statics(relaxed=False):
        y = None if y_eq is None else model.relaxed(np.asarray(y_eq, dtype=float))
        return _linearize(model, y, equilibrium_rtol)


def _linearize(model: RodModel, y_eq: np.ndarray | None, equilibrium_rtol: float
               ) -> Linearization:
    st = RodStatics(model)
    y0 = model.initial_state() if y_eq is None else np.array(y_eq, dtype=float)
    if y0.shape != (model.n,):
        raise ValueError(f"y_eq must have shape ({model.n},), got {y0.shape}")
    if not np.all(np.isfinite(y0)):
        raise ValueError("y_eq contains non-finite values")
    y0[model.velocity_mask] = 0.0
    p = model.p_index  # (N, 4)
    pq = y0[p]
    y0[p] = pq / np.linalg.norm(pq, axis=1)[:, None]
    _check_equilibrium(st, y0, equilibrium_rtol)
    zero = np.zeros(model.n)
    Fy = model.dF_dy_sparse(0.0, y0, zero).tocsr()
    Fp = model.dF_dyp_sparse(0.0, y0, zero).tocsr()
    ns = st.n_static
    T = st.tangent(y0).tocsc()  # positions/rotations -> dy
    # velocities in the static layout: node 0 v, then per cell (Omega_i, v_i)
    vel_rows = st.static_rows  # the same state indices (v and Omega entries)
    S = sp.csc_matrix((np.ones(ns), (vel_rows, np.arange(ns))), shape=(model.n, ns))
    mom = vel_rows  # momentum rows: rows of v (linear) and Omega (angular momentum)
    # kinematic rows: phi rows as they are, quaternion rows projected with 4 G(p)^T
    th_dofs = st.theta_cols.ravel()
    ph_dofs = st.phi_cols.ravel()
    Pphi = sp.csr_matrix((np.ones(ph_dofs.size), (ph_dofs, model.phi_index.ravel())),
                         shape=(ns, model.n))
    Rth = sp.csr_matrix((np.ones(th_dofs.size), (th_dofs, np.arange(th_dofs.size))),
                        shape=(ns, th_dofs.size))
    P = (Pphi + Rth @ (4.0 * T.T).tocsr()[th_dofs]).tocsr()  # 4 G(p)^T on the p rows
    keep = np.setdiff1d(np.arange(ns), st.fixed_cols)
    Tk, Sk = T[:, keep], S[:, keep]
    Fm, Pm = Fy[mom[keep]], Fp[mom[keep]]
    M = (Pm @ Sk).tocsc()
    C = (Fm @ Sk).tocsc()
    K = (Fm @ Tk).tocsc()
    Mq = (Pm @ Tk).tocsc()  # y'-dependence of the momentum rows on positions (zero here)
    Pk = P[keep]
    Ekin = (Pk @ Fp @ Tk).tocsc()
    Akin_q = (Pk @ Fy @ Tk).tocsc()
    Akin_w = (Pk @ Fy @ Sk).tocsc()
    E = sp.bmat([[Ekin, (Pk @ Fp @ Sk)], [Mq, M]]).tocsc()
    A = sp.bmat([[Akin_q, Akin_w], [K, C]]).tocsc()
    if model.branches:
        # generalized Maxwell: the internal strains z join the state, x = (q, w, z); their
        # rows z' = (strain(q) - z)/theta and their resultants' coupling into the momentum
        z = np.concatenate([model.q_segment_index.ravel(), model.q_joint_index.ravel()])
        Kz = Fm[:, z]
        Zq, Zw, Zz = (Fy[z] @ Tk).tocsc(), (Fy[z] @ Sk).tocsc(), Fy[z][:, z].tocsc()
        nz = z.size
        E = sp.bmat([[E, None], [None, Fp[z][:, z]]]).tocsc()
        A = sp.bmat([[A, sp.vstack([sp.csc_matrix((keep.size, nz)), Kz])],
                     [sp.hstack([Zq, Zw]), Zz]]).tocsc()
    for m in (M, C, K, E, A):
        m.eliminate_zeros()
    return Linearization(model=model, y_eq=y0, dofs=keep, M=M, C=C, K=K, E=E, A=A, T=T,
                         statics=st)


# --------------------------------------------------------------------------------------
# Modes
# --------------------------------------------------------------------------------------


@dataclass
class Mode:
    """One mode of the linearised damped rod (SI units, angular frequencies in rad/s).

    index: 1-based rank by natural frequency; family: one of :data:`FAMILIES`;
    family_index: 1-based rank within its family; omega: undamped natural angular
    frequency from ``K phi = omega^2 M phi``; eigenvalues: the damped pair (1/s);
    zeta: damping ratio of the pair; omega_damped: ``|Im lambda|`` (0 if overdamped);
    zeta_modal: ``phi^T C phi / (2 omega phi^T M phi)`` (uncoupled modal damping, a check);
    energy_fractions: strain-energy fractions of :data:`STRAIN_COMPONENTS`;
    displacement (3, N+1) node displacement (m) and rotation (3, N) segment rotation
    (rad, material) of the mass-normalised undamped mode shape; analytic_omega: the
    continuum beam/bar value where known (straight clamped-free rod), else None.
    A rigid mode (family ``rigid``, not resisted by the stiffness) has omega 0,
    eigenvalues (0, 0), zeta and zeta_modal NaN (no damping ratio: ``None`` in
    :meth:`to_dict`) and zero energy fractions. An overdamped mode of which only one of
    its two real eigenvalues could be found has the other NaN, zeta NaN and a ``doubt``.
    """

    index: int
    family: str
    family_index: int
    omega: float
    eigenvalues: tuple[complex, complex]
    zeta: float
    omega_damped: float
    zeta_modal: float
    energy_fractions: dict[str, float]
    displacement: np.ndarray = field(repr=False)
    rotation: np.ndarray = field(repr=False)
    analytic_omega: float | None = None
    #: why this mode's damped values are doubtful ("" when they are not): printed by
    #: ``kvrod modes`` and kept in modes.json
    doubt: str = ""

    @property
    def frequency_hz(self) -> float:
        """Natural frequency omega / (2 pi) (Hz)."""
        return self.omega / (2 * math.pi)

    @property
    def eigenvalue(self) -> complex:
        """The damped eigenvalue with Im >= 0 (the slower one if overdamped), 1/s."""
        return self.eigenvalues[0]

    def to_dict(self, shapes: bool = True) -> dict:
        """JSON-ready dict (complex numbers as [re, im], arrays as nested lists; without
        ``displacement`` and ``rotation`` if not ``shapes``)."""
        d = asdict(self)
        d["eigenvalues"] = [[float(z.real), float(z.imag)] for z in self.eigenvalues]
        if shapes:
            d["displacement"] = self.displacement.tolist()
            d["rotation"] = self.rotation.tolist()
        else:
            del d["displacement"], d["rotation"]
        d["frequency_hz"] = self.frequency_hz
        for key in ("zeta", "zeta_modal"):   # a rigid mode has no damping ratio
            if not math.isfinite(d[key]) and self.family == "rigid":
                d[key] = None
        return d


def _strain_energy_fractions(lin: Linearization, Q: np.ndarray) -> np.ndarray:
    """Strain energy per component (k, 6) of real reduced mode vectors Q (nq, k), J.

    A rod with coupled sections (full 6x6 matrices) has no energy per component; each
    component c gets its share ``1/2 e_c (C e)_c`` of the quadratic form (the couplings'
    energy split half to the strain, half to the curvature), which sums to the strain
    energy (docs/design.md, section 10)."""
    if getattr(lin.model, "coupled", False):
        return _coupled_strain_energies(lin, Q)
    return np.stack([np.sum(c**2, axis=1) for c in _strain_vectors(lin, Q)], axis=1)


def _mode_strains(lin: Linearization, dx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linearised strains (dV (3, N), dU (3, N+1)) of a reduced mode vector expanded to
    ``dx``, by central differences of ``RodModel.diagnostics`` along the retraction."""
    model, st = lin.model, lin.statics
    L = float(np.sum(model.arrays.seg_field("h")))
    th = dx[st.theta_cols]
    scale = max(float(np.max(np.abs(dx[st.phi_cols.ravel()]))) / L,
                float(np.max(np.abs(th))), 1e-300)
    eps = 1e-6 / scale
    with model.statics():
        sp_ = model.diagnostics(0.0, st.static_retract(lin.y_eq, eps * dx))["strains"]
        sm_ = model.diagnostics(0.0, st.static_retract(lin.y_eq, -eps * dx))["strains"]
    return (sp_["V"] - sm_["V"]) / (2 * eps), (sp_["U"] - sm_["U"]) / (2 * eps)


def _coupled_strain_energies(lin: Linearization, Q: np.ndarray) -> np.ndarray:
    """The shares of :func:`_strain_energy_fractions` for a coupled rod (k, 6), J."""
    a = lin.model.arrays
    N = a.N
    h = a.seg_field("h")[:, 0]
    CFF = a.segc_field("C_FF").reshape(N, 3, 3)
    CFM = a.segc_field("C_FM").reshape(N, 3, 3)
    w = a.segc_field("w")
    CMM = a.jntc_field("C_MM").reshape(N + 1, 3, 3)
    wU = a.jnt_field("h")[:, 0].copy()
    wU[0] = wU[0] if a.clamped("start") else 0.0
    wU[-1] = wU[-1] if a.clamped("end") else 0.0
    out = np.zeros((Q.shape[1], 6))
    for k in range(Q.shape[1]):
        dV, dU = (x.T for x in _mode_strains(lin, lin.expand(Q[:, k])))   # (N, 3), (N+1, 3)
        kbar = w[:, :1] * dU[:-1] + w[:, 1:] * dU[1:]                      # (N, 3)
        out[k, :3] = np.sum(0.5 * h[:, None] * dV * np.einsum("nij,nj->ni", CFF, dV)
                            + 0.5 * dV * np.einsum("nij,nj->ni", CFM, kbar), axis=0)
        out[k, 3:] = (np.sum(0.5 * wU[:, None] * dU * np.einsum("nij,nj->ni", CMM, dU),
                             axis=0)
                      + np.sum(0.5 * kbar * np.einsum("nji,nj->ni", CFM, dV), axis=0))
    return out


def _strain_vectors(lin: Linearization, Q: np.ndarray) -> list[np.ndarray]:
    """Energy-weighted linearised strains per component: list of 6 (k, m) arrays.

    Strains by central differences of ``RodModel.diagnostics`` along the retraction
    ``static_retract``; weights ``sqrt(h C / 2)`` (segments) and ``sqrt(h_j C_M / 2)``
    (joints; h_j = h/2 at a clamp), so the squared norms are strain energies (J).
    """
    a = lin.model.arrays
    h = a.seg_field("h")[:, 0]
    CF, CM = a.seg_field("C_F").T, a.jnt_field("C_M").T          # (3, N), (3, N+1)
    wU = a.jnt_field("h")[:, 0].copy()
    wU[0] = wU[0] if a.clamped("start") else 0.0
    wU[-1] = wU[-1] if a.clamped("end") else 0.0
    comps: list[list[np.ndarray]] = [[] for _ in range(6)]
    for k in range(Q.shape[1]):
        dV, dU = _mode_strains(lin, lin.expand(Q[:, k]))
        for c in range(3):
            comps[c].append(np.sqrt(0.5 * CF[c] * h) * dV[c])
            comps[3 + c].append(np.sqrt(0.5 * CM[c] * wU) * dU[c])
    return [np.array(c) for c in comps]


def _classify(fr: np.ndarray) -> str:
    """Family from the six energy fractions (V1, V2, V3, U1, U2, U3)."""
    scores = {"shear": fr[0] + fr[1], "axial": fr[2], "bending-1": fr[3],
              "bending-2": fr[4], "torsion": fr[5]}
    return max(scores, key=scores.get)


def _clusters(omega: np.ndarray, rtol: float = 1e-6) -> list[np.ndarray]:
    groups: list[list[int]] = []
    for k, w in enumerate(omega):
        if groups and abs(w - omega[groups[-1][-1]]) <= rtol * max(abs(w), 1e-300):
            groups[-1].append(k)
        else:
            groups.append([k])
    return [np.array(g) for g in groups]


def _separate_degenerate(lin: Linearization, omega: np.ndarray, Phi: np.ndarray,
                         Mmat) -> np.ndarray:
    """Rotate bases of (numerically) repeated frequencies to pure strain families.

    Within a cluster the vectors are rotated to make the energy matrices of the strain
    components diagonal as far as possible (successively U1, U2, U3, V3), then
    M-orthonormalised again.
    """
    Phi = Phi.copy()
    for g in _clusters(omega):
        if g.size < 2:
            continue
        X = Phi[:, g]
        G = X.T @ (Mmat @ X)  # M-orthonormal basis of the cluster first
        X = np.linalg.solve(np.linalg.cholesky(0.5 * (G + G.T)), X.T).T
        comps = _strain_vectors(lin, X)
        mats = [c @ c.T for c in comps]  # (s, s) each
        total = sum(mats)
        for key in (3, 4, 5, 2):
            _, R = la.eigh(mats[key] + 1e-3 * mats[(key + 1) % 6], total)
            if np.ptp(np.diag(R.T @ mats[key] @ R) / np.diag(R.T @ total @ R)) > 0.5:
                break
        X = X @ R
        G = X.T @ (Mmat @ X)
        Lc = np.linalg.cholesky(0.5 * (G + G.T))
        Phi[:, g] = np.linalg.solve(Lc, X.T).T
    return Phi


#: components within this relative distance of the largest magnitude count as tied
SIGN_TIE_RTOL = 1e-6


def fix_sign(v: np.ndarray) -> np.ndarray:
    """``v`` or ``-v``: the one whose largest-magnitude component (the first of those
    within :data:`SIGN_TIE_RTOL` of it, in index order) is positive. A zero vector is
    returned as it is."""
    a = np.abs(v)
    top = float(a.max(initial=0.0))
    if top == 0.0:
        return v
    k = int(np.argmax(a >= (1.0 - SIGN_TIE_RTOL) * top))
    return -v if v[k] < 0 else v


def _fix_signs(X: np.ndarray) -> np.ndarray:
    """:func:`fix_sign` applied to every column of ``X``."""
    return np.column_stack([fix_sign(X[:, k]) for k in range(X.shape[1])]) if X.shape[1] \
        else X


def _pair_zeta(l1: complex, l2: complex) -> tuple[float, float]:
    """(natural frequency sqrt(l1 l2), damping ratio -(l1 + l2)/(2 sqrt(l1 l2)))."""
    prod = (l1 * l2).real
    wn = math.sqrt(max(prod, 0.0))
    return wn, (-(l1 + l2).real / (2 * wn) if wn > 0 else math.inf)


def _near(a: complex, b: complex, rtol: float = 1e-6) -> bool:
    return abs(a - b) <= rtol * max(abs(a), abs(b), 1e-300)


def _assign(lams: np.ndarray, Pmat: np.ndarray, omega: np.ndarray,
            nmodes: int) -> list[list[complex]]:
    """Match damped eigenvalues (one per conjugate pair, Im >= 0) to undamped modes.

    Pmat[j, k]: participation of undamped mode k in damped eigenvector j. A complex
    eigenvalue fills a mode (it stands for its conjugate pair), a real one half of it.
    Eigenvalues go greedily (largest participation first) to clusters of repeated natural
    frequencies; inside a cluster each group of (numerically) equal eigenvalues is shared
    one copy per mode, so arbitrary mixtures of degenerate eigenvectors do not matter.
    """
    groups = [g for g in _clusters(omega[:nmodes])]
    Pc = np.stack([Pmat[:, g].sum(axis=1) for g in groups], axis=1)
    need = np.where(np.abs(lams.imag) > 0, 2, 1)
    slots = np.zeros(len(groups))
    cap = np.array([2 * g.size for g in groups])
    owner = np.full(lams.size, -1)
    for flat in np.argsort(-Pc, axis=None):
        j, c = divmod(int(flat), Pc.shape[1])
        if owner[j] >= 0 or slots[c] + need[j] > cap[c]:
            continue
        owner[j] = c
        slots[c] += need[j]
    out: list[list[complex]] = [[] for _ in range(nmodes)]
    for c, g in enumerate(groups):
        js = list(np.flatnonzero(owner == c))
        mslots = {int(k): 0 for k in g}
        while js:
            j0 = js.pop(0)
            same = [j0] + [j for j in js if _near(lams[j], lams[j0])]
            js = [j for j in js if j not in same]
            score = Pmat[np.array(same)][:, g].sum(axis=0)
            for j in same:
                for k in g[np.argsort(-score)]:
                    if mslots[int(k)] + need[j] <= 2 and not any(
                            _near(lams[j], v) for v in out[int(k)]):
                        out[int(k)].append(complex(lams[j]))
                        mslots[int(k)] += need[j]
                        break
    return out


def _finish_pair(vals: list[complex]) -> tuple[complex, complex]:
    if len(vals) == 1 and abs(vals[0].imag) > 0:
        return vals[0], vals[0].conjugate()
    if len(vals) == 2:
        if not all(map(cmath.isfinite, vals)):     # a partner not found: NaN second
            return tuple(sorted(vals, key=lambda z: not cmath.isfinite(z)))
        a, b = sorted(vals, key=lambda z: -z.real)
        return a, b
    if len(vals) == 1:  # a lone real eigenvalue (the partner not found)
        return vals[0], complex(math.nan)
    return complex(math.nan), complex(math.nan)


def _overdamped_pair(so, phi: np.ndarray, vals: list[complex]) -> tuple[list[complex], str]:
    """The two real eigenvalues of an overdamped Kelvin-Voigt mode, checked against the
    mode's own quadratic ``phi^T T(mu) phi = 0`` (exact for proportional damping, where
    its roots multiply to omega^2): one value near each of its two roots, a missing one
    refined from its root by Rayleigh-functional steps on T (``_SecondOrder.polish``).
    Why: near a high target the slow roots of all overdamped modes crowd at about
    -1/tau (within 1e-5), so the participation-based assignment can give a mode a
    neighbour's slow root in place of its own fast one, or leave it one root (zeta came
    out 1 where it is 126). Returns the pair (NaN for a root not found) and a doubt ("" if
    none). Modes whose quadratic is not clearly overdamped (roots within a factor 4) and
    generalized Maxwell rods (whose real roots are no modes) are left as assigned."""
    if not so.ok or so.groups or any(v.imag != 0 for v in vals):
        return vals, ""
    m, c, k = (float(phi @ (X @ phi)) for X in (so.M, so.C, so.K))
    roots = np.roots([m, c, k])
    if np.any(roots.imag != 0) or np.any(roots.real >= 0):
        return vals, ""
    slow, fast = sorted(roots.real, key=abs)
    if fast / slow < 4.0:
        return vals, ""
    out: list[complex] = []
    for r in (slow, fast):
        near = [v for v in vals
                if v.real < 0 and abs(math.log(v.real / r)) < 0.5 * math.log(fast / slow)]
        if near:
            out.append(min(near, key=lambda v: abs(v.real - r)))
            continue
        got = complex(so.polish(np.array([r]), phi[:, None])[0])
        if abs(got.imag) <= 1e-7 * abs(got) and abs(got.real - r) <= 1e-2 * abs(r):
            out.append(complex(got.real, 0.0))
        else:
            return [*out, complex(math.nan)], ("only one of the two real eigenvalues of "
                                                "this overdamped mode was found: no "
                                                "damping ratio")
    return out, ""


def _m_orthonormal(Z: np.ndarray, M) -> np.ndarray:
    """Z (nq, k) with M-orthonormal columns spanning the same space (Cholesky: column j
    mixes columns 0..j only, so the order of the columns is kept)."""
    if Z.shape[1] == 0:
        return Z
    G = Z.T @ (M @ Z)
    Lc = np.linalg.cholesky(0.5 * (G + G.T))
    return la.solve_triangular(Lc, Z.T, lower=True).T


def _rigid_subspaces(lin: Linearization) -> tuple[np.ndarray, np.ndarray]:
    """(Z_all, Z_null): M-orthonormal bases (nq, k) of the rigid motions the supports leave
    free at ``y_eq`` and of the part of them the stiffness does not resist (|K z| and
    |K^T z| below ``RIGID_NULL_RTOL`` |K| |z|: round-off)."""
    motions = lin.statics.rigid_motions(lin.y_eq)
    if motions.k == 0:
        empty = np.zeros((lin.nq, 0))
        return empty, empty
    Z = _m_orthonormal(motions.basis[lin.dofs], lin.M)
    K = lin.K
    absK = abs(K)
    size = float(np.max(np.linalg.norm(absK @ np.abs(Z), axis=0)
                        + np.linalg.norm(absK.T @ np.abs(Z), axis=0)))
    W = np.vstack([np.asarray(K @ Z), np.asarray(K.T @ Z)]) / max(size, 1e-300)
    if np.all(np.linalg.norm(W, axis=0) <= RIGID_NULL_RTOL):
        return Z, Z                                   # unloaded: all of them (the rule)
    _, sv, Vt = np.linalg.svd(W, full_matrices=False)
    null = Vt[sv <= RIGID_NULL_RTOL].T                # (k, k0) combinations
    if null.shape[1] == 0:
        return Z, np.zeros((lin.nq, 0))
    # a basis of their span that does not depend on the LAPACK build: the unit vectors
    # projected on it, in order
    P = null @ null.T
    cols: list[np.ndarray] = []
    for e in np.eye(Z.shape[1]):
        v = P @ e
        for u in cols:
            v = v - (u @ v) * u
        if np.linalg.norm(v) > 1e-6:
            cols.append(v / np.linalg.norm(v))
        if len(cols) == null.shape[1]:
            break
    return Z, _m_orthonormal(Z @ np.column_stack(cols), lin.M)


def _singular(exc: Exception) -> ValueError:
    return ValueError(
        "the linearised stiffness at y_eq is singular beyond the rigid motions its "
        f"supports leave free (a mechanism, or a buckling load): no modes ({exc})")


def _rigid_participation(Z: np.ndarray, M, X: np.ndarray) -> np.ndarray:
    """Fraction of the M-norm of each column of X (real or complex) in span(Z)
    (Z M-orthonormal)."""
    if Z.shape[1] == 0 or X.shape[1] == 0:
        return np.zeros(X.shape[1])
    c = Z.T @ (M @ X)
    nrm = np.real(np.einsum("ij,ij->j", X.conj(), M @ X))
    return np.sum(np.abs(c) ** 2, axis=0) / np.maximum(nrm, 1e-300)


def _dense_modes(lin: Linearization, Zn: np.ndarray):
    M, K = lin.M.toarray(), lin.K.toarray()
    Q = None
    if Zn.shape[1]:
        # elastic modes on the M-orthogonal complement of the unresisted rigid motions
        # (exact: K Z = 0 and Z^T K = 0 there)
        Q = la.null_space((M @ Zn).T)
        K, M = Q.T @ K @ Q, Q.T @ M @ Q
    symmetric = np.allclose(K, K.T, rtol=0.0, atol=1e-12 * np.abs(K).max())
    if symmetric:
        w2, Phi = la.eigh(0.5 * (K + K.T), 0.5 * (M + M.T))  # straight, unloaded
    else:
        w2, Phi = la.eig(K, M)  # geometric stiffness of a loaded state
    order = np.argsort(w2.real)
    w2, Phi = w2.real[order], Phi[:, order].real
    if Q is not None:
        Phi = Q @ Phi
    if not symmetric:   # eig may return one vector twice for a repeated eigenvalue
        Phi = _span_clusters(lin, np.sqrt(np.maximum(w2, 0.0)), Phi, symmetric=False)
    Mf = lin.M.toarray()
    Phi /= np.sqrt(np.einsum("ik,ij,jk->k", Phi, Mf, Phi))[None, :]
    lam, X = _pencil_eigen(lin)
    lam, Xq = _upper_half(lam, X[: lin.nq])
    if Zn.shape[1]:   # the (defective) zero eigenvalues of the rigid motions
        keep = _rigid_participation(Zn, lin.M, Xq) < 0.5
        lam, Xq = lam[keep], Xq[:, keep]
    return w2, Phi, lam, Xq


def _pencil_eigen(lin: Linearization) -> tuple[np.ndarray, np.ndarray]:
    """All eigenvalues and eigenvectors of the first-order pencil ``-A x = lambda E x``.

    Kelvin-Voigt: E = [[I, 0], [*, M]] is regular, and the standard eigenproblem of
    E^-1 A is ~3x faster than QZ. Generalized Maxwell: the rows of the internal strains
    carry the rates 1/tau_b (1e12 1/s for tau_b = 1e-12 s); E^-1 A puts them next to rows
    of order 1..1e4 and the slow eigenvalues drown in its rounding (the first bending mode
    of examples/maxwell_cantilever.toml with tau_1 = 1e-12 s came out at 5.5 rad/s with a
    negative damping ratio for 3.57). The QZ algorithm on the pencil with its rows
    equilibrated (each row of [A E] scaled to max 1: the eigenvalues do not change) is
    backward stable row by row, so the fast branches stay where they are (eigenvalues
    ~ -1/tau_b) and the slow ones keep their accuracy."""
    Ed, Ad = lin.E.toarray(), lin.A.toarray()
    if not lin.model.branches:
        return la.eig(la.solve(Ed, -Ad))
    d = 1.0 / np.maximum(np.max(np.abs(Ad), axis=1), np.max(np.abs(Ed), axis=1))
    lam, X = la.eig(-Ad * d[:, None], Ed * d[:, None])
    return lam, X


def _upper_half(lam: np.ndarray, X: np.ndarray, rtol: float = 1e-7):
    """One eigenvalue of each conjugate pair (Im > 0) and all real ones (Im := 0).

    |Im| <= rtol |lambda| counts as real (rounding of repeated real eigenvalues)."""
    lam = np.asarray(lam, dtype=complex)
    fin = np.isfinite(lam)
    real = fin & (np.abs(lam.imag) <= rtol * np.abs(lam))
    keep = real | (fin & (lam.imag > 0))
    lam = np.where(real, lam.real + 0j, lam)
    return lam[keep], X[:, keep]


def _start_vector(n: int, dtype=float) -> np.ndarray:
    """A fixed start vector for ARPACK (its default is random: results would vary by run)."""
    v = np.random.default_rng(20131105).standard_normal(n)
    return v.astype(dtype)


def _is_symmetric(K: sp.spmatrix) -> bool:
    d = abs(K - K.T)
    return d.nnz == 0 or d.max() <= 1e-12 * abs(K).max()


def _span_clusters(lin: Linearization, omega: np.ndarray, Phi: np.ndarray,
                   symmetric: bool | None = None) -> np.ndarray:
    """Make every cluster of repeated frequencies span its whole eigenspace.

    Non-symmetric ARPACK (``eigs``, needed for the geometric stiffness of a loaded state)
    does not orthogonalise eigenvectors of a repeated eigenvalue: for the degenerate
    bending pairs of a square section it may return two nearly parallel vectors, even the
    same one twice, depending on its random start vector (``kvrod modes --n-elements 80``
    then failed one run in three in the energy-metric Cholesky). Such a cluster is
    recomputed by shift-invert subspace iteration at its frequency, from the vectors found
    plus fixed random ones, and a Rayleigh-Ritz step that cannot return parallel vectors
    either: for a symmetric K (M is SPD) ``eigh`` of the projected pencil, whose vectors
    are M-orthonormal; otherwise the ordered QZ decomposition (``ordqz``), whose Schur
    vectors give an orthonormal basis of the cluster's deflating subspace, M-orthonormalised
    (a non-symmetric ``eig`` may return one eigenvector twice for a repeated eigenvalue:
    that is how this step failed on another machine). ``symmetric``: which of the two
    (default: whether K is symmetric).
    """
    if symmetric is None:
        symmetric = _is_symmetric(lin.K)
    Phi = Phi.copy()
    for g in _clusters(omega):
        if g.size < 2:
            continue
        X = Phi[:, g]
        G = X.T @ (lin.M @ X)
        if la.eigvalsh(0.5 * (G + G.T))[0] > 1e-6 * np.trace(G) / g.size:
            continue
        sigma = omega[g[0]] ** 2 * (1 - 1e-6)
        lu = spla.splu((lin.K - sigma * lin.M).tocsc())
        rng = np.random.default_rng(7)
        Z = np.column_stack([X, rng.standard_normal((X.shape[0], 2))])
        for _ in range(6):
            Z = lu.solve(np.asarray(lin.M @ Z))
            Z, _ = np.linalg.qr(Z)
        Kr, Mr = Z.T @ (lin.K @ Z), Z.T @ (lin.M @ Z)
        target = omega[g[0]] ** 2
        if symmetric:
            w2, C = la.eigh(0.5 * (Kr + Kr.T), 0.5 * (Mr + Mr.T))
            pick = np.sort(np.argsort(np.abs(w2 - target))[: g.size])
            Phi[:, g] = Z @ C[:, pick]
        else:
            lam = la.eigvals(Kr, Mr)
            dist = np.abs(lam - target)
            cut = np.sort(dist)[g.size - 1] * (1 + 1e-9) + 1e-300

            def near(alpha, beta, cut=cut, target=target):
                with np.errstate(divide="ignore", invalid="ignore"):
                    return np.abs(alpha / beta - target) <= cut

            *_, Zs = la.ordqz(Kr, Mr, sort=near, output="complex")
            V = (Z @ Zs[:, : g.size])
            V = np.column_stack([V.real, V.imag]) if np.iscomplexobj(V) else V
            # a real basis of the subspace (its vectors' real and imaginary parts), the
            # g.size directions of largest M-norm, M-orthonormal
            G = V.T @ (lin.M @ V)
            ev, W = la.eigh(0.5 * (G + G.T))
            Phi[:, g] = _m_orthonormal(V @ W[:, ::-1][:, : g.size], lin.M)
    return Phi


def _select(omega: np.ndarray, k0: int, count: int, target: float) -> tuple[int, np.ndarray]:
    """The modes shown: (how many of the k0 unresisted rigid modes, indices into ``omega``
    (ascending) of the others).

    Rule: the ``count`` modes whose natural frequency is nearest ``target`` (rad/s; 0: the
    lowest), the rigid modes (omega 0) competing like any other. A cluster of repeated
    frequencies (relative 1e-6, e.g. a twin bending pair) ranks by the frequency of its
    first member, so it is taken whole unless the count ends inside it; ties keep the
    order rigid modes first, then ascending omega (within a cluster: the order of
    :func:`_separate_degenerate`)."""
    cand = np.r_[np.zeros(k0), omega]
    head = np.empty(cand.size)
    for g in _clusters(cand):
        head[g] = cand[g[0]]
    chosen = np.sort(np.argsort(np.abs(head - target), kind="stable")[:count])
    return int(np.sum(chosen < k0)), chosen[chosen >= k0] - k0


def _covered(w2: np.ndarray, k0: int, count: int, target: float) -> bool:
    """Whether the m eigenvalues w2 nearest target^2 (as shift-invert returns them) hold
    every mode :func:`_select` would pick from all of them: a mode not among them lies
    farther from target^2 than all of them in omega^2, so it is farther in omega than the
    farthest one picked when that one's distance d satisfies d (2 target + d) < the
    largest omega^2 distance found."""
    if target == 0.0:
        return True
    omega = np.sqrt(np.maximum(w2, 0.0))
    _, sel = _select(omega, k0, count, target)
    if sel.size == 0:
        return True
    d = float(np.max(np.abs(omega[sel] - target)))
    return d * (2 * target + d) < float(np.max(np.abs(w2 - target**2)))


def modal_analysis(model: RodModel, y_eq: np.ndarray | None = None, count: int = 10,
                   dense_max: int = 0, target: float | None = None) -> list[Mode]:
    """The ``count`` lowest modes (or those nearest ``target``) of the rod linearised at
    ``y_eq`` (see module docstring).

    Parameters
    ----------
    model : RodModel
        The rod; its loads (as in statics) apply at ``y_eq``.
    y_eq : ndarray, optional
        Equilibrium state (n,); default the reference.
    count : int
        Number of modes (>= 1).
    dense_max : int
        Largest reduced size ``nq`` solved with dense LAPACK, every eigenvalue of the
        pencil (the test oracle; a generalized Maxwell rod up to
        ``MAXWELL_DENSE_MAX`` unknowns). Default 0: the sparse method
        (:mod:`runtime.analysis.modal_sparse`) at every size where it applies (``count``
        + 6 modes fewer than the unknowns), dense below.
    target : float, optional
        Natural angular frequency (rad/s, >= 0): the ``count`` modes whose natural
        frequency is nearest to it instead of the lowest (module docstring). Their
        ``index`` and ``family_index`` then count within the modes returned.

    Returns
    -------
    list of Mode
        Sorted by undamped natural frequency: omega (rad/s), damping ratio zeta of the
        eigenvalue pair, family, mode shape; the rigid modes the supports leave free
        (family ``rigid``, omega 0) first, counted in ``count``. Continuum reference
        values are attached by the command line from the independent ``references``
        package.
    """
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise ValueError(f"count = {count!r} must be an integer >= 1")
    if target is not None and (isinstance(target, bool) or not isinstance(
            target, (int, float, np.integer, np.floating)) or not math.isfinite(target)
            or target < 0):
        raise ParameterError("target", target, "a finite natural angular frequency >= 0 "
                             "rad/s (None: the lowest modes)", where="modal_analysis")
    w_t = 0.0 if target is None else float(target)
    lin = linearize(model, y_eq)
    if count > lin.nq:
        raise ValueError(f"count = {count} exceeds the {lin.nq} degrees of freedom")
    maxwell = model.branches > 0
    Z_all, Zn = _rigid_subspaces(lin)
    k0 = Zn.shape[1]
    from runtime.analysis import modal_sparse as ms

    m = count + ms.EXTRA_MODES if target is not None else max(count - k0, 1) + \
        ms.EXTRA_MODES
    dense = lin.nq <= dense_max or m > lin.nq - k0 - 2
    if dense:
        if maxwell and lin.E.shape[0] > MAXWELL_DENSE_MAX:
            raise ValueError(f"the linearised generalized Maxwell rod has {lin.E.shape[0]} "
                             f"unknowns (internal strains included); the dense solver "
                             f"takes at most {MAXWELL_DENSE_MAX} (use the sparse one: "
                             f"dense_max below {lin.nq})")
        w2, Phi, lam, Xq = _dense_modes(lin, Zn)
        errs = np.zeros(lam.size)
        omega = np.sqrt(np.maximum(w2, 0.0))
        n_rigid, sel = _select(omega, k0, count, w_t)
        lo = max(int(sel.min()) - ms.EXTRA_MODES, 0) if sel.size else 0
        hi = min(int(sel.max()) + 1 + ms.EXTRA_MODES, omega.size) if sel.size else 0
    else:
        if w_t > 0:
            # above the spectrum the nearest modes are the highest ones, in the same order
            # for every such target: shift at the spectrum's upper bound instead
            w_t = min(w_t, math.sqrt(ms.highest_omega2(lin)))
        while True:
            w2, Phi = ms.undamped_modes(lin, m, Zn, w_t**2)
            if _covered(w2, k0, count, w_t) or m >= lin.nq - k0 - 2:
                break
            m = min(2 * m, lin.nq - k0 - 2)
        omega = np.sqrt(np.maximum(w2, 0.0))
        n_rigid, sel = _select(omega, k0, count, w_t)
        lam, Xq, errs = ms.sparse_modes(lin, sel, w2, Phi, maxwell, Zn, w_t**2)
        lo, hi = 0, omega.size
    if maxwell:
        # the real eigenvalues are the relaxation of the internal strains (and overdamped
        # motion, not identified here): the modes are the oscillatory pairs
        osc = np.abs(lam.imag) > 0
        lam, Xq, errs = lam[osc], Xq[:, osc], errs[osc]
    Phi = _fix_signs(_separate_degenerate(lin, omega, Phi, lin.M))
    Zn = _fix_signs(Zn)
    # participation of the undamped modes in every damped eigenvector (M-weighted)
    c = Phi[:, lo:hi].T @ (lin.M @ Xq)  # (modes, eigvecs)
    Pmat = np.abs(c.T) ** 2
    Pmat /= np.maximum(np.real(np.einsum("ij,ij->i", Xq.T.conj(), (lin.M @ Xq).T)), 1e-300
                       )[:, None]
    pairs = _assign(lam, Pmat, omega[lo:hi], hi - lo) if hi > lo else []
    used = [v for k in sel for v in pairs[k - lo]]

    def backward_error(v: complex) -> float:
        return float(errs[int(np.argmin(np.abs(lam - v)))]) if lam.size else 0.0

    worst = max((backward_error(v) for v in used), default=0.0)
    if worst > ms.BACKWARD_ERROR_WARN:
        warnings.warn(f"kvrod: a damped eigenvalue was refined only to a backward error of "
                      f"{worst:.1e} in the pencil (doubtful)", RuntimeWarning, stacklevel=2)
    energies = _strain_energy_fractions(lin, Phi[:, sel]) if sel.size else np.zeros((0, 6))
    rigid_share = _rigid_participation(Z_all, lin.M, Phi[:, sel])
    modes: list[Mode] = []
    family_count: dict[str, int] = {}
    for j in range(n_rigid):      # the unresisted rigid motions: omega = 0
        dx = lin.expand(Zn[:, j])
        family_count["rigid"] = j + 1
        modes.append(Mode(index=j + 1, family="rigid", family_index=j + 1, omega=0.0,
                          eigenvalues=(0j, 0j), zeta=math.nan, omega_damped=0.0,
                          zeta_modal=math.nan,
                          energy_fractions=dict.fromkeys(STRAIN_COMPONENTS, 0.0),
                          displacement=dx[lin.statics.phi_cols].T,
                          rotation=dx[lin.statics.theta_cols].T))
    Cd = lin.C
    second_order = None
    # omega^2 below this is round-off of the eigensolvers (eps ~ 1e-16 times the largest
    # stiffness-to-mass ratio, with room for n and the conditioning)
    w2_floor = 1e-12 * float(np.max(np.abs(lin.K.diagonal()) / lin.M.diagonal()))
    for i, k in enumerate(sel):
        e = energies[i]
        fr = e / e.sum() if e.sum() > 0 else e
        fam = "rigid" if rigid_share[i] > 0.5 else _classify(fr)
        family_count[fam] = family_count.get(fam, 0) + 1
        vals, doubt = list(pairs[k - lo]), ""
        if not maxwell and vals and abs(w2[k]) > w2_floor:
            if second_order is None:
                second_order = ms._SecondOrder(lin)
            vals, doubt = _overdamped_pair(second_order, Phi[:, k], vals)
        worst_k = max((backward_error(v) for v in pairs[k - lo]), default=0.0)
        if worst_k > ms.BACKWARD_ERROR_WARN:
            doubt = (f"eigenvalue refined only to a backward error of {worst_k:.1e} in the "
                     "pencil")
        l1, l2 = _finish_pair(vals)
        wn, zeta = _pair_zeta(l1, l2)
        if doubt.startswith("only one"):
            zeta = math.nan
        phi = Phi[:, k]
        w = float(omega[k])
        zm = float(phi @ (Cd @ phi)) / (2 * w) if w > 0 else math.inf
        if fam == "rigid" and abs(w2[k]) <= w2_floor:   # unresisted to round-off
            w, l1, l2, zeta, zm = 0.0, 0j, 0j, math.nan, math.nan
        if maxwell:   # frequency-dependent moduli: the natural frequency is |lambda|, and
            w, zm = wn, math.nan               # there is no constant damping matrix
        dx = lin.expand(phi)
        disp = dx[lin.statics.phi_cols].T
        rot = dx[lin.statics.theta_cols].T
        modes.append(Mode(index=len(modes) + 1, family=fam, family_index=family_count[fam],
                          omega=w, eigenvalues=(l1, l2), zeta=float(zeta),
                          omega_damped=float(abs(l1.imag)), zeta_modal=zm,
                          energy_fractions=dict(zip(STRAIN_COMPONENTS, map(float, fr),
                                                    strict=True)),
                          displacement=disp, rotation=rot, doubt=doubt))
    return modes


def family_retardation_time(model: RodModel, family: str) -> float:
    """The Kelvin-Voigt retardation time of a family (s): V/C of its governing entry at
    mid-rod.

    bending-1: V_M[0]/C_M[0] (tau_E, or tau~_E on the naive route), bending-2:
    V_M[1]/C_M[1], torsion: V_M[2]/C_M[2] (tau_S), axial: V_F[2]/C_F[2], shear: tau_S.
    """
    a = model.arrays
    i, j = model.N // 2, max(model.N // 2, 1)
    CF, VF = a.seg_field("C_F")[i], a.seg_field("V_F")[i]
    CM, VM = a.jnt_field("C_M")[j], a.jnt_field("V_M")[j]
    table = {"bending-1": VM[0] / CM[0], "bending-2": VM[1] / CM[1],
             "torsion": VM[2] / CM[2], "axial": VF[2] / CF[2], "shear": VF[0] / CF[0]}
    return float(table[family])
