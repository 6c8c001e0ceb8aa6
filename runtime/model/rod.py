"""The discrete Cosserat rod with Kelvin-Voigt damping on the generated kernels.

:class:`RodModel` exposes the IDA residual ``F(t, y, y') = 0`` of the discrete rod
(``derive/discrete_rod.py``; layout in ``generated/rod_layout.py``), its banded iteration
matrix ``dF/dy + cj dF/dy'`` in LAPACK band storage, diagnostics (energies, dissipation
rate 2D, external power, strains and stress resultants) and the static problem in reduced
coordinates. Hot paths call the compiled C API through ctypes (``runtime/model/build.py``); if
no compiler is available the same per-element CasADi kernels are evaluated in-process
(vectorised with ``Function.map``) with identical numbers up to rounding.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np
import scipy.sparse as sp

from generated import rod_layout as L
from runtime.errors import ParameterError
from runtime.model import build

BOUNDARY_CONDITIONS = ("clamped", "pinned", "free")
DAMPING_ROUTES = ("consistent", "naive")


# --------------------------------------------------------------------------------------
# Parameters
# --------------------------------------------------------------------------------------


def _check_positive(name: str, value: float) -> None:
    if not (isinstance(value, (int, float, np.floating, np.integer)) and math.isfinite(value)
            and value > 0):
        raise ParameterError(name, value, "finite and > 0")


@dataclass(frozen=True)
class RodParameters:
    """Material and geometry of a straight rod with a rectangular section (SI units).

    length L (m), n_elements N (-), density rho (kg/m^3), youngs_modulus E (Pa),
    poisson_ratio nu (-), tau_S, tau_B retardation times (s, paper Sect. 1),
    width, height of the rectangle (m; width along the first director d1, height along d2),
    shear_correction: apply kappa_alpha and J_T (eq. (7)) or not (eq. (2)),
    damping: "consistent" (eqs. (4)-(9)) or "naive" (resultant route).
    """

    length: float
    n_elements: int
    density: float
    youngs_modulus: float
    poisson_ratio: float
    tau_S: float
    tau_B: float
    width: float
    height: float
    shear_correction: bool = True
    damping: str = "consistent"

    def __post_init__(self) -> None:
        for name in ("length", "density", "youngs_modulus", "width", "height"):
            _check_positive(name, getattr(self, name))
        nu = self.poisson_ratio
        if not (isinstance(nu, (int, float, np.floating)) and math.isfinite(nu)
                and -1.0 < nu <= 0.5):
            raise ParameterError("poisson_ratio", nu, "-1 < nu <= 1/2")
        for name in ("tau_S", "tau_B"):
            tau = getattr(self, name)
            if not (isinstance(tau, (int, float, np.floating)) and math.isfinite(tau)
                    and tau >= 0):
                raise ParameterError(name, tau, "finite and >= 0")
        n = self.n_elements
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ParameterError("n_elements", n, "integer >= 1")
        if self.damping not in DAMPING_ROUTES:
            raise ParameterError("damping", self.damping, f"one of {DAMPING_ROUTES}")

    @property
    def element_length(self) -> float:
        """h = L/N (m)."""
        return self.length / self.n_elements

    def section(self) -> dict[str, float]:
        """Section constants A, I1, I2, I3, J_T, kappa_1..3 (shear corrections applied or 1)."""
        sec = dict(_constitutive().rectangle_section(self.width, self.height,
                                                     self.poisson_ratio))
        if not self.shear_correction:
            sec.update(kappa_1=1.0, kappa_2=1.0, kappa_3=1.0)
        return sec

    def matrices(self) -> dict[str, np.ndarray]:
        """Diagonals of C_F, C_M, V_F, V_M (eqs. (2)/(7), (9)) and rho A, rho I (3,)."""
        c = _constitutive()
        s = self.section()
        E, nu = self.youngs_modulus, self.poisson_ratio
        geo = (s["A"], s["I1"], s["I2"], s["I3"], s["kappa_1"], s["kappa_2"], s["kappa_3"])
        C_F, C_M = c.stiffness_matrices(E, nu, *geo)
        V_F, V_M = c.damping_matrices(E, nu, self.tau_S, self.tau_B, *geo,
                                      route=self.damping)
        out = {}
        for name, m in (("C_F", C_F), ("C_M", C_M), ("V_F", V_F), ("V_M", V_M)):
            m = np.asarray(m, dtype=float)
            if m.ndim == 2:
                if np.any(m - np.diag(np.diag(m))):
                    raise ValueError(f"{name} is not diagonal; the kernels take diagonals")
                m = np.diag(m)
            out[name] = m.copy()
        out["rhoA"] = np.array([self.density * s["A"]])
        out["rhoI"] = self.density * np.array([s["I1"], s["I2"], s["I3"]])
        return out


def _constitutive():
    """generated/constitutive.py (stiffness and damping from the derivation, eqs. (2)-(9))."""
    from generated import constitutive

    return constitutive


# --------------------------------------------------------------------------------------
# Layout helpers
# --------------------------------------------------------------------------------------


def _i_phi(i: int) -> int:
    return L.CELL0_OFFSETS["phi"] if i == 0 else L.cell_start(i) + L.OFF_PHI


def _i_v(i: int) -> int:
    return L.CELL0_OFFSETS["v"] if i == 0 else L.cell_start(i) + L.OFF_V


def _i_p(i: int) -> int:
    return L.cell_start(i) + L.OFF_P


def _i_om(i: int) -> int:
    return L.cell_start(i) + L.OFF_OMEGA


def _r3(i0):
    return np.asarray(i0)[..., None] + np.arange(3)


def _r4(i0):
    return np.asarray(i0)[..., None] + np.arange(4)


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Quaternion product (scalar first), shapes (4,) or (..., 4)."""
    a0, av, b0, bv = a[..., 0], a[..., 1:], b[..., 0], b[..., 1:]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a0 * b0 - np.sum(av * bv, axis=-1)
    out[..., 1:] = a0[..., None] * bv + b0[..., None] * av + np.cross(av, bv)
    return out


def quat_exp(theta: np.ndarray) -> np.ndarray:
    """exp((0, theta)/2) = (cos(|theta|/2), sin(|theta|/2) theta/|theta|), shape (..., 4)."""
    th = np.asarray(theta, dtype=float)
    a = np.linalg.norm(th, axis=-1)
    out = np.empty(th.shape[:-1] + (4,))
    out[..., 0] = np.cos(a / 2)
    sinc = np.where(a > 1e-8, np.sin(a / 2) / np.where(a > 0, a, 1.0), 0.5 - a**2 / 48)
    out[..., 1:] = sinc[..., None] * th
    return out


def quat_rotation(p: np.ndarray) -> np.ndarray:
    """R(p) (3,3), homogeneous of degree 0 (same formula as the kernels)."""
    p0, q = p[0], p[1:]
    qx = np.array([[0, -q[2], q[1]], [q[2], 0, -q[0]], [-q[1], q[0], 0]])
    return ((p0**2 - q @ q) * np.eye(3) + 2 * np.outer(q, q) + 2 * p0 * qx) / (p @ p)


def _ptr(a: np.ndarray, n: int, fortran: bool = False) -> int:
    """Data address of a contiguous (C, or Fortran if asked) float64 array of size >= n."""
    ok = isinstance(a, np.ndarray) and a.dtype == np.float64 and a.size >= n and (
        a.flags.f_contiguous if fortran else a.flags.c_contiguous)
    if not ok:
        order = "Fortran" if fortran else "C"
        raise TypeError(f"expected a {order}-contiguous float64 numpy array of size >= {n}")
    return a.ctypes.data


class _PointerCache:
    """Data addresses of the last few arrays seen (``ndarray.ctypes.data`` costs ~3 us).

    Holding a reference keeps an array alive and its buffer fixed (numpy refuses to
    resize referenced arrays), so an identity hit always returns the right address.
    """

    def __init__(self, size: int = 8) -> None:
        self._arrays: list[np.ndarray] = []
        self._ptrs: list[int] = []
        self._size = size

    def __call__(self, a: np.ndarray, n: int, fortran: bool = False) -> int:
        for k, b in enumerate(self._arrays):
            if b is a:
                return self._ptrs[k]
        ptr = _ptr(a, n, fortran)
        self._arrays.insert(0, a)
        self._ptrs.insert(0, ptr)
        del self._arrays[self._size:], self._ptrs[self._size:]
        return ptr


# --------------------------------------------------------------------------------------
# In-process CasADi backend (fallback, and reference for the compiled kernels)
# --------------------------------------------------------------------------------------


def load_kernels(gdir: Path | None = None) -> dict[str, ca.Function]:
    """The serialised per-element kernels generated/rod_*.casadi, by name."""
    gdir = gdir or build.generated_dir()
    return {name: ca.Function.deserialize((gdir / f"{name}.casadi").read_text())
            for name in L.KERNELS}


class CasadiBackend:
    """Assembly of the rod from the .casadi kernels with NumPy (vectorised with map)."""

    def __init__(self, n_elements: int, kernels: dict[str, ca.Function] | None = None):
        N = self.N = n_elements
        self.k = kernels or load_kernels()
        self.maps: dict[tuple[str, int], ca.Function] = {}
        nodes, segs = np.arange(N + 1), np.arange(1, N + 1)
        self.n_phi = _r3([_i_phi(i) for i in nodes])
        self.n_v = _r3([_i_v(i) for i in nodes])
        self.s_p = _r4([_i_p(i) for i in segs])
        self.s_om = _r3([_i_om(i) for i in segs])
        self.n6 = np.concatenate([self.n_phi, self.n_v], axis=1)
        self.s7 = np.concatenate([self.s_p, self.s_om], axis=1)
        self.seg_rows = np.concatenate([self.n_v[:-1], self.n_v[1:], self.s_om], axis=1)
        # reduced segment Jacobian columns (phi_b, p, v_b, Omega) and their partners
        self.seg_cols_b = np.concatenate([self.n_phi[1:], self.s_p, self.n_v[1:], self.s_om],
                                         axis=1)
        self.seg_cols_a = np.concatenate([self.n_phi[:-1], self.n_v[:-1]], axis=1)
        self.seg_partner = np.r_[0:3, 7:10]
        self.jnt_rows = np.concatenate([self.s_om[:-1], self.s_om[1:]], axis=1)
        self.jnt_cols = np.concatenate([self.s_p[:-1], self.s_p[1:], self.s_om[:-1],
                                        self.s_om[1:]], axis=1)

    def _map(self, name: str, n: int) -> ca.Function:
        key = (name, n)
        if key not in self.maps:
            self.maps[key] = self.k[name].map(n)
        return self.maps[key]

    def _call(self, name: str, n: int, *args) -> list[np.ndarray]:
        out = self._map(name, n).call([ca.DM(np.atleast_2d(np.asarray(a, float)))
                                       if np.ndim(a) != 1 else ca.DM(a) for a in args])
        return [np.array(o) for o in out]

    def _node_args(self, par, y, yp):
        N = self.N
        m = np.full(N + 1, par[L.PARAM_OFFSETS["rhoA"]] * par[L.PARAM_OFFSETS["h"]])
        m[[0, -1]] *= 0.5
        tip = (np.arange(N + 1) == N).astype(float)
        fixed = np.zeros(N + 1)
        fixed[0], fixed[-1] = par[L.PARAM_OFFSETS["fix_start"]], par[L.PARAM_OFFSETS["fix_end"]]
        return (y[self.n_phi].T, y[self.n_v].T, yp[self.n_phi].T, yp[self.n_v].T,
                m[None], tip[None], fixed[None])

    def _seg_args(self, y):
        return (y[self.n_phi[:-1]].T, y[self.n_phi[1:]].T, y[self.s_p].T, y[self.n_v[:-1]].T,
                y[self.n_v[1:]].T, y[self.s_om].T)

    def _seg_weights(self, par):
        w = np.ones((self.N, 9))
        if par[L.PARAM_OFFSETS["fix_start"]] > 0.5:
            w[0, 0:3] = 0
        if par[L.PARAM_OFFSETS["fix_end"]] > 0.5:
            w[-1, 3:6] = 0
        return w

    def _boundary_joints(self, par, y):
        """(args, rows, cols, which) for the clamp joints present."""
        N, out = self.N, []
        hh = 0.5 * par[L.PARAM_OFFSETS["h"]]
        o = L.PARAM_OFFSETS
        z = np.zeros(3)
        if par[o["clamp_start"]] > 0.5:
            ps = par[o["p_start"]:o["p_start"] + 4]
            out.append(((ps, y[self.s_p[0]], z, y[self.s_om[0]], hh),
                        self.s_om[0], np.concatenate([self.s_p[0], self.s_om[0]]),
                        slice(3, 6), np.r_[4:8, 11:14]))
        if par[o["clamp_end"]] > 0.5:
            pe = par[o["p_end"]:o["p_end"] + 4]
            out.append(((y[self.s_p[N - 1]], pe, y[self.s_om[N - 1]], z, hh),
                        self.s_om[N - 1], np.concatenate([self.s_p[N - 1], self.s_om[N - 1]]),
                        slice(0, 3), np.r_[0:4, 8:11]))
        return out

    def residual(self, par, y, yp, res) -> None:
        N = self.N
        res[:] = 0.0
        (rn,) = self._call("rod_node_inertia", N + 1, *self._node_args(par, y, yp), par)
        res[self.n6] = rn.T
        (rs,) = self._call("rod_segment_inertia", N, y[self.s_p].T, y[self.s_om].T,
                           yp[self.s_p].T, yp[self.s_om].T, par)
        res[self.s7] = rs.T
        res[self.s_om[-1]] -= np.array(self.k["rod_tip_moment"](y[self.s_p[-1]], par)).ravel()
        (Q,) = self._call("rod_segment_forces", N, *self._seg_args(y), par)
        np.subtract.at(res, self.seg_rows, Q.T * self._seg_weights(par))
        h = par[L.PARAM_OFFSETS["h"]]
        if N > 1:
            (T,) = self._call("rod_joint_torques", N - 1, y[self.s_p[:-1]].T, y[self.s_p[1:]].T,
                              y[self.s_om[:-1]].T, y[self.s_om[1:]].T, h, par)
            np.subtract.at(res, self.jnt_rows, T.T)
        for args, rows, _, which, _ in self._boundary_joints(par, y):
            T = np.array(self.k["rod_joint_torques"](*args, par)).ravel()
            res[rows] -= T[which]

    def jacobian_band(self, par, y, yp, cy, cj, ab) -> None:
        N, kl, ku = self.N, L.KL, L.KU
        ab[kl:] = 0.0

        def scatter(rows, cols, vals):
            r = np.broadcast_to(rows[..., :, None], vals.shape)
            c = np.broadcast_to(cols[..., None, :], vals.shape)
            np.add.at(ab, (kl + ku + r - c, c), vals)

        (Jn,) = self._call("rod_node_inertia_jac", N + 1, *self._node_args(par, y, yp), par,
                           cy, cj)
        scatter(self.n6, self.n6, Jn.reshape(6, N + 1, 6).transpose(1, 0, 2))
        (Js,) = self._call("rod_segment_inertia_jac", N, y[self.s_p].T, y[self.s_om].T,
                           yp[self.s_p].T, yp[self.s_om].T, par, cy, cj)
        scatter(self.s7, self.s7, Js.reshape(7, N, 7).transpose(1, 0, 2))
        if cy == 0.0:
            return
        Jm = np.array(self.k["rod_tip_moment_jac"](y[self.s_p[-1]], par))
        scatter(self.s_om[-1], self.s_p[-1], -cy * Jm)
        (Jq,) = self._call("rod_segment_forces_jac", N, *self._seg_args(y), par)
        Jq = cy * Jq.reshape(6, N, 13).transpose(1, 0, 2)  # (N, 6, 13)
        w = self._seg_weights(par)
        Jb = Jq * w[:, 3:9, None]
        Ja = -Jq[:, 0:3] * w[:, 0:3, None]
        rows_b, rows_a = self.seg_rows[:, 3:9], self.seg_rows[:, 0:3]
        pc = self.seg_partner
        scatter(rows_b, self.seg_cols_b, -Jb)
        scatter(rows_b, self.seg_cols_a, Jb[:, :, pc])
        scatter(rows_a, self.seg_cols_b, -Ja)
        scatter(rows_a, self.seg_cols_a, Ja[:, :, pc])
        h = par[L.PARAM_OFFSETS["h"]]
        if N > 1:
            (Jt,) = self._call("rod_joint_torques_jac", N - 1, y[self.s_p[:-1]].T,
                               y[self.s_p[1:]].T, y[self.s_om[:-1]].T, y[self.s_om[1:]].T, h,
                               par)
            scatter(self.jnt_rows, self.jnt_cols,
                    -cy * Jt.reshape(6, N - 1, 14).transpose(1, 0, 2))
        for args, rows, cols, which, cidx in self._boundary_joints(par, y):
            Jt = np.array(self.k["rod_joint_torques_jac"](*args, par))
            scatter(rows, cols, -cy * Jt[which][:, cidx])

    def diagnostics(self, par, y, out) -> None:
        N = self.N
        out[:] = 0.0
        ns = len(L.DIAG_SCALARS)
        nargs = self._node_args(par, y, y)
        tipn = nargs[5]
        Tn, Pn = self._call("rod_node_kinetic", N + 1, nargs[1], nargs[4], tipn, par)
        fixed = nargs[6].ravel() > 0.5
        out[0] += Tn.sum()
        out[3] += Pn.ravel()[~fixed].sum()
        tip = (np.arange(1, N + 1) == N).astype(float)[None]
        Ts, Ps = self._call("rod_segment_kinetic", N, y[self.s_p].T, y[self.s_om].T, tip, par)
        out[0] += Ts.sum()
        out[3] += Ps.sum()
        W, D, V, F = self._call("rod_segment_diagnostics", N, *self._seg_args(y), par)
        out[1] += W.sum()
        out[2] += 2 * D.sum()
        out[ns:ns + 3 * N] = V.T.ravel()
        out[ns + 3 * N:ns + 6 * N] = F.T.ravel()
        oU, oM = ns + 6 * N, ns + 6 * N + 3 * (N + 1)
        h = par[L.PARAM_OFFSETS["h"]]
        if N > 1:
            Wj, Dj, U, M = self._call("rod_joint_diagnostics", N - 1, y[self.s_p[:-1]].T,
                                      y[self.s_p[1:]].T, y[self.s_om[:-1]].T,
                                      y[self.s_om[1:]].T, h, par)
            out[1] += Wj.sum()
            out[2] += 2 * Dj.sum()
            out[oU + 3:oU + 3 * N] = U.T.ravel()
            out[oM + 3:oM + 3 * N] = M.T.ravel()
        for args, _, _, which, _ in self._boundary_joints(par, y):
            Wj, Dj, U, M = (np.array(v).ravel()
                            for v in self.k["rod_joint_diagnostics"](*args, par))
            j = 0 if which.start == 3 else N
            out[1] += Wj[0]
            out[2] += 2 * Dj[0]
            out[oU + 3 * j:oU + 3 * j + 3] = U
            out[oM + 3 * j:oM + 3 * j + 3] = M


# --------------------------------------------------------------------------------------
# The model
# --------------------------------------------------------------------------------------


class RodModel:
    """Discrete Kelvin-Voigt Cosserat rod in IDA form (see module docstring).

    start, end: "clamped" (position and frame), "pinned" (position) or "free".
    tip_force (N) acts on node N, tip_moment (N m, spatial) on segment N, gravity (m/s^2)
    on the nodal masses; all scaled by :attr:`load_scale`. The reference configuration is
    straight along e3 with node 0 at the origin and the identity frame.
    """

    def __init__(self, params: RodParameters, start: str = "clamped", end: str = "free",
                 tip_force=(0.0, 0.0, 0.0), tip_moment=(0.0, 0.0, 0.0),
                 gravity=(0.0, 0.0, 0.0), backend: str = "auto") -> None:
        for name, bc in (("start", start), ("end", end)):
            if bc not in BOUNDARY_CONDITIONS:
                raise ParameterError(name, bc, f"one of {BOUNDARY_CONDITIONS}")
        for name, vec in (("tip_force", tip_force), ("tip_moment", tip_moment),
                          ("gravity", gravity)):
            arr = np.asarray(vec, dtype=float)
            if arr.shape != (3,) or not np.all(np.isfinite(arr)):
                raise ParameterError(name, vec, "3 finite numbers")
        if backend not in ("auto", "c", "casadi"):
            raise ParameterError("backend", backend, "'auto', 'c' or 'casadi'")
        self.params, self.start, self.end = params, start, end
        N = self.N = params.n_elements
        self.n = L.n_state(N)
        self.kl, self.ku = L.KL, L.KU
        self.ldab = 2 * self.kl + self.ku + 1
        self.n_static = L.n_static(N)
        self.kl_static, self.ku_static = L.STATIC_KL, L.STATIC_KU
        self._par = np.zeros(L.N_PARAMS)
        self._set("h", params.element_length)
        for name, val in params.matrices().items():
            self._set(name, val)
        self._set("gravity", gravity)
        self._set("tip_force", tip_force)
        self._set("tip_moment", tip_moment)
        self._set("load_scale", 1.0)
        self._set("p_start", (1.0, 0.0, 0.0, 0.0))
        self._set("p_end", (1.0, 0.0, 0.0, 0.0))
        self._set("fix_start", float(start != "free"))
        self._set("clamp_start", float(start == "clamped"))
        self._set("fix_end", float(end != "free"))
        self._set("clamp_end", float(end == "clamped"))
        self.differential = np.ones(self.n, dtype=bool)
        if start != "free":
            self.differential[_i_v(0):_i_v(0) + 3] = False
        if end != "free":
            self.differential[_i_v(N):_i_v(N) + 3] = False
        lib = None if backend == "casadi" else build.load_library()
        if backend == "c" and lib is None:
            raise RuntimeError("compiled backend requested but no library could be built")
        self._lib = lib
        self._casadi: CasadiBackend | None = None if lib is not None else CasadiBackend(N)
        self._pp = self._par.ctypes.data
        self._ptrs = _PointerCache()
        self._zeros = np.zeros(self.n)
        self._ab = np.zeros((self.ldab, self.n), order="F")
        self._pattern: sp.csc_matrix | None = None
        self._pattern_flat = np.zeros(0, dtype=np.intp)
        self._diag = np.zeros(L.diagnostics_size(N))
        nodes = np.arange(N + 1)
        self._static_rows = np.concatenate(
            [np.arange(_i_v(0), _i_v(0) + 3)]
            + [np.r_[_i_om(i):_i_om(i) + 3, _i_v(i):_i_v(i) + 3] for i in range(1, N + 1)])
        self._phi_idx = _r3([_i_phi(i) for i in nodes])
        self._p_idx = _r4([_i_p(i) for i in range(1, N + 1)])
        # static unknowns (reduced coordinates) from the layout module
        self._static_phi_cols = np.array([L.static_phi(i) for i in nodes])[:, None] \
            + np.arange(3)
        self._static_theta_cols = np.array([L.static_theta(i) for i in range(1, N + 1)])[
            :, None] + np.arange(3)
        fixed_cols = [] if start == "free" else [0, 1, 2]
        fixed_cols += [] if end == "free" else list(self._static_phi_cols[-1])
        self._static_fixed = sp.csr_matrix(
            (np.ones(len(fixed_cols)), (fixed_cols, fixed_cols)),
            shape=(self.n_static, self.n_static))
        self._vel_mask = np.zeros(self.n, dtype=bool)
        self._vel_mask[_r3([_i_v(i) for i in nodes]).ravel()] = True
        self._vel_mask[_r3([_i_om(i) for i in range(1, N + 1)]).ravel()] = True

    # -- parameters ---------------------------------------------------------------------
    @property
    def par(self) -> np.ndarray:
        """The kernel parameter vector (generated/rod_layout.PARAMS); edit in place only."""
        return self._par

    def _set(self, name: str, value) -> None:
        k, s = L.PARAM_OFFSETS[name], L.PARAM_SIZES[name]
        self._par[k:k + s] = np.asarray(value, dtype=float).ravel()

    def parameter(self, name: str) -> np.ndarray:
        """A named slice of the kernel parameter vector (copy)."""
        k, s = L.PARAM_OFFSETS[name], L.PARAM_SIZES[name]
        return self._par[k:k + s].copy()

    @property
    def backend(self) -> str:
        """'c' (compiled, ctypes) or 'casadi' (in-process fallback)."""
        return "c" if self._lib is not None else "casadi"

    @property
    def load_scale(self) -> float:
        """Factor on all external loads (the static solver steps it from 0 to 1)."""
        return float(self._par[L.PARAM_OFFSETS["load_scale"]])

    @load_scale.setter
    def load_scale(self, value: float) -> None:
        if not math.isfinite(value):
            raise ParameterError("load_scale", value, "finite")
        self._par[L.PARAM_OFFSETS["load_scale"]] = value

    # -- states -------------------------------------------------------------------------
    def initial_state(self) -> np.ndarray:
        """Straight reference along e3 at rest (shape (n,))."""
        y = np.zeros(self.n)
        h = self.params.element_length
        for i in range(self.N + 1):
            y[_i_phi(i) + 2] = i * h
        for i in range(1, self.N + 1):
            y[_i_p(i)] = 1.0
        return y

    def positions(self, y: np.ndarray) -> np.ndarray:
        """Node positions phi (3, N+1)."""
        return y[self._phi_idx].T.copy()

    def quaternions(self, y: np.ndarray) -> np.ndarray:
        """Segment quaternions p (4, N), scalar part first."""
        return y[self._p_idx].T.copy()

    def tip_position(self, y: np.ndarray) -> np.ndarray:
        """phi_N (3,) (m)."""
        k = _i_phi(self.N)
        return y[k:k + 3].copy()

    # -- IDA residual and Jacobian ------------------------------------------------------
    def residual(self, t: float, y: np.ndarray, yp: np.ndarray, out: np.ndarray) -> None:
        """out <- F(t, y, y') (n,)."""
        if self._lib is not None:
            n = self.n
            P = self._ptrs
            rc = self._lib.kvrod_residual(self.N, self._pp, t, P(y, n), P(yp, n), P(out, n))
            if rc:
                raise RuntimeError(f"kvrod_residual failed ({rc})")
        else:
            self._casadi.residual(self._par, y, yp, out)

    def jacobian_band2(self, t: float, y: np.ndarray, yp: np.ndarray, cy: float, cj: float,
                       out_ab: np.ndarray) -> None:
        """out_ab <- cy dF/dy + cj dF/dy' in LAPACK band storage (2 kl + ku + 1, n), 'F'."""
        self._band(self._par, t, y, yp, cy, cj, out_ab)

    def _band(self, par, t, y, yp, cy, cj, out_ab) -> None:
        if out_ab.shape != (self.ldab, self.n) or not out_ab.flags.f_contiguous:
            raise TypeError(f"out_ab must be a Fortran-ordered array of shape "
                            f"{(self.ldab, self.n)}")
        if self._lib is not None:
            n = self.n
            rc = self._lib.kvrod_jacobian_band2(self.N, _ptr(par, L.N_PARAMS), t, _ptr(y, n),
                                                _ptr(yp, n), cy, cj, self.ldab,
                                                out_ab.ctypes.data)
            if rc:
                raise RuntimeError(f"kvrod_jacobian_band failed ({rc})")
        else:
            self._casadi.jacobian_band(par, y, yp, cy, cj, out_ab)

    def jacobian_band(self, t: float, y: np.ndarray, yp: np.ndarray, cj: float,
                      out_ab: np.ndarray) -> None:
        """out_ab <- dF/dy + cj dF/dy' in LAPACK band storage (2 kl + ku + 1, n), order 'F'."""
        if self._lib is not None:
            if out_ab.shape != (self.ldab, self.n) or not out_ab.flags.f_contiguous:
                raise TypeError(f"out_ab must be a Fortran-ordered array of shape "
                                f"{(self.ldab, self.n)}")
            n = self.n
            P = self._ptrs
            rc = self._lib.kvrod_jacobian_band(self.N, self._pp, t, P(y, n), P(yp, n), cj,
                                               self.ldab, P(out_ab, self.ldab * n, True))
            if rc:
                raise RuntimeError(f"kvrod_jacobian_band failed ({rc})")
        else:
            self.jacobian_band2(t, y, yp, 1.0, cj, out_ab)

    def _band_to_csc(self, ab: np.ndarray, kl: int, ku: int) -> sp.csc_matrix:
        n = ab.shape[1]
        offsets = ku - np.arange(kl + ku + 1)
        m = sp.dia_matrix((ab[kl:], offsets), shape=(n, n)).tocsc()
        m.eliminate_zeros()
        return m

    def sparsity(self) -> sp.csc_matrix:
        """Structural pattern of dF/dy + c dF/dy' (CSC of ones), fixed for this model.

        Found by evaluating the banded Jacobian at two random states with all loads switched
        on (so no entry vanishes by accident); the same boundary conditions as the model.
        """
        if self._pattern is None:
            rng = np.random.default_rng(12345)
            par = self._par.copy()
            for name in ("gravity", "tip_force", "tip_moment"):
                k, sz = L.PARAM_OFFSETS[name], L.PARAM_SIZES[name]
                par[k:k + sz] = rng.uniform(0.5, 1.5, sz)
            par[L.PARAM_OFFSETS["load_scale"]] = 1.0
            acc = np.zeros((self.ldab, self.n), order="F")
            ab = np.zeros((self.ldab, self.n), order="F")
            for _ in range(2):
                y = self.initial_state() + 0.1 * rng.standard_normal(self.n)
                self._band(par, 0.0, y, rng.standard_normal(self.n), 1.0, 1.0, ab)
                acc[self.kl:] += np.abs(ab[self.kl:])
            m = self._band_to_csc(acc, self.kl, self.ku)
            m.sort_indices()
            m.data[:] = 1.0
            cols = np.repeat(np.arange(self.n), np.diff(m.indptr))
            self._pattern = m
            self._pattern_flat = (self.kl + self.ku + m.indices - cols) + cols * self.ldab
        return self._pattern.copy()

    def jacobian_sparse(self, t: float, y: np.ndarray, yp: np.ndarray,
                        cj: float) -> sp.csc_matrix:
        """dF/dy + cj dF/dy' as CSC with the fixed pattern of :meth:`sparsity`."""
        return self._sparse(t, y, yp, 1.0, cj)

    def _sparse(self, t, y, yp, cy, cj) -> sp.csc_matrix:
        pat = self.sparsity()
        ab = self._ab
        self.jacobian_band2(t, y, yp, cy, cj, ab)
        pat.data = ab.ravel(order="F")[self._pattern_flat].copy()
        return pat

    def dF_dy_sparse(self, t: float, y: np.ndarray, yp: np.ndarray) -> sp.csc_matrix:
        """dF/dy (CSC, fixed pattern of :meth:`sparsity`)."""
        return self._sparse(t, y, yp, 1.0, 0.0)

    def dF_dyp_sparse(self, t: float, y: np.ndarray, yp: np.ndarray) -> sp.csc_matrix:
        """dF/dy' (CSC, fixed pattern of :meth:`sparsity`)."""
        return self._sparse(t, y, yp, 0.0, 1.0)

    # -- diagnostics --------------------------------------------------------------------
    def _eval_diagnostics(self, t: float, y: np.ndarray, yp: np.ndarray | None) -> np.ndarray:
        out = self._diag
        if self._lib is not None:
            n = self.n
            yp_ = self._zeros if yp is None else yp
            rc = self._lib.kvrod_diagnostics(self.N, self._pp, t, _ptr(y, n), _ptr(yp_, n),
                                             _ptr(out, out.size))
            if rc:
                raise RuntimeError(f"kvrod_diagnostics failed ({rc})")
        else:
            self._casadi.diagnostics(self._par, y, out)
        return out

    def energy_scalars(self, t: float, y: np.ndarray,
                       yp: np.ndarray | None = None) -> tuple[float, float, float, float]:
        """(T, W, 2D, P_ext) of state y in J, J, W, W — the scalars of :meth:`diagnostics`
        without building its per-element arrays (the energy audit calls this per step)."""
        out = self._eval_diagnostics(t, y, yp)
        return float(out[0]), float(out[1]), float(out[2]), float(out[3])

    def diagnostics(self, t: float, y: np.ndarray, yp: np.ndarray | None = None) -> dict:
        """Energies and resultants of state y.

        Returns kinetic T (J), elastic W (J), dissipation_rate 2D (W), external_power (W),
        strains V (3, N) on segments and U (3, N+1) at joints (joint j at node j; the
        clamp joints j = 0, N are zero when absent), material resultants F (3, N) (N) and
        M (3, N+1) (N m), each elastic + viscous (eq. (1)).
        """
        out = self._eval_diagnostics(t, y, yp)
        N, ns = self.N, len(L.DIAG_SCALARS)
        res = {name: float(out[k]) for k, name in enumerate(L.DIAG_SCALARS)}
        V = out[ns:ns + 3 * N].reshape(N, 3).T.copy()
        F = out[ns + 3 * N:ns + 6 * N].reshape(N, 3).T.copy()
        U = out[ns + 6 * N:ns + 6 * N + 3 * (N + 1)].reshape(N + 1, 3).T.copy()
        M = out[ns + 6 * N + 3 * (N + 1):].reshape(N + 1, 3).T.copy()
        res["strains"] = {"V": V, "U": U}
        res["resultants"] = {"F": F, "M": M}
        return res

    # -- static problem -----------------------------------------------------------------
    def _at_rest(self, y: np.ndarray) -> np.ndarray:
        y0 = np.array(y, dtype=float)
        y0[self._vel_mask] = 0.0
        return y0

    def static_residual(self, y: np.ndarray, out: np.ndarray) -> None:
        """Force/torque balance at rest under load_scale (n_static,), reduced rows.

        Rows: node 0 forces, then per cell i: segment i torques (material), node i forces.
        A fixed node's rows are 0 (its increment is held at 0 by an identity row).
        """
        r = np.empty(self.n)
        self.residual(0.0, self._at_rest(y), self._zeros, r)
        out[:] = r[self._static_rows]

    def _static_jacobian_csr(self, y: np.ndarray) -> sp.csr_matrix:
        y0 = self._at_rest(y)
        ab = np.zeros((self.ldab, self.n), order="F")
        self.jacobian_band2(0.0, y0, self._zeros, 1.0, 0.0, ab)
        Jd = self._band_to_csc(ab, self.kl, self.ku).tocsr()[self._static_rows]
        return (Jd @ self._static_tangent(y0)).tocsr() + self._static_fixed

    def _static_tangent(self, y: np.ndarray) -> sp.csc_matrix:
        """T (n x n_static): dy = T dx; dphi -> phi (identity), dtheta -> dp = 1/2 L(p) [0; I]."""
        N = self.N
        p = y[self._p_idx]  # (N, 4)
        p0, q = p[:, 0], p[:, 1:]
        z = np.zeros(N)
        qx = np.stack([np.stack([z, -q[:, 2], q[:, 1]], -1),
                       np.stack([q[:, 2], z, -q[:, 0]], -1),
                       np.stack([-q[:, 1], q[:, 0], z], -1)], 1)  # [q]x, (N, 3, 3)
        Lm = np.empty((N, 4, 3))
        Lm[:, 0, :] = -q
        Lm[:, 1:, :] = p0[:, None, None] * np.eye(3) + qx
        Lm *= 0.5
        rows_p = np.broadcast_to(self._p_idx[:, :, None], (N, 4, 3))
        cols_p = np.broadcast_to(self._static_theta_cols[:, None, :], (N, 4, 3))
        rows = np.concatenate([self._phi_idx.ravel(), rows_p.ravel()])
        cols = np.concatenate([self._static_phi_cols.ravel(), cols_p.ravel()])
        vals = np.concatenate([np.ones(self._phi_idx.size), Lm.ravel()])
        return sp.csc_matrix((vals, (rows, cols)), shape=(self.n, self.n_static))

    # -- index maps for linearisations (modal analysis) ------------------------------
    @property
    def phi_index(self) -> np.ndarray:
        """State indices of the node positions, shape (N+1, 3)."""
        return self._phi_idx

    @property
    def p_index(self) -> np.ndarray:
        """State indices of the segment quaternions, shape (N, 4)."""
        return self._p_idx

    @property
    def velocity_mask(self) -> np.ndarray:
        """Boolean mask of the velocity unknowns (v, Omega) in y."""
        return self._vel_mask

    @property
    def static_rows(self) -> np.ndarray:
        """State/residual indices of the momentum rows, in static-vector order."""
        return self._static_rows

    @property
    def static_phi_cols(self) -> np.ndarray:
        """Static-vector indices of the node positions, shape (N+1, 3)."""
        return self._static_phi_cols

    @property
    def static_theta_cols(self) -> np.ndarray:
        """Static-vector indices of the segment rotation increments, shape (N, 3)."""
        return self._static_theta_cols

    def static_tangent(self, y: np.ndarray) -> sp.csc_matrix:
        """dy/d(dphi, dtheta) at y: the map from static increments to state changes."""
        return self._static_tangent(y)

    def static_jacobian_sparse(self, y: np.ndarray) -> sp.csc_matrix:
        """d(static residual)/d(dphi, dtheta) at dx = 0 (CSC)."""
        return self._static_jacobian_csr(y).tocsc()

    def static_jacobian_band(self, y: np.ndarray, out_ab: np.ndarray) -> None:
        """Static Jacobian in LAPACK band storage (2 kl_static + ku_static + 1, n_static)."""
        kl, ku = self.kl_static, self.ku_static
        if out_ab.shape != (2 * kl + ku + 1, self.n_static):
            raise TypeError(f"out_ab must have shape {(2 * kl + ku + 1, self.n_static)}")
        c = self._static_jacobian_csr(y).tocoo()
        out_ab[:] = 0.0
        if c.nnz and (np.max(c.row - c.col) > kl or np.max(c.col - c.row) > ku):
            raise RuntimeError("static Jacobian outside its band")  # pragma: no cover
        np.add.at(out_ab, (kl + ku + c.row - c.col, c.col), c.data)

    def static_retract(self, y: np.ndarray, dx: np.ndarray) -> np.ndarray:
        """New state: phi += dphi, p <- p*exp(dtheta/2) renormalised; velocities kept."""
        y1 = np.array(y, dtype=float)
        dx = np.asarray(dx)
        y1[self._phi_idx] += dx[self._static_phi_cols]
        p = y1[self._p_idx]
        p = quat_mul(p, quat_exp(dx[self._static_theta_cols]))
        y1[self._p_idx] = p / np.linalg.norm(p, axis=1)[:, None]
        return y1

    # -- whole-rod CasADi function (IDAS cross-check) -----------------------------------
    def casadi_residual_function(self) -> ca.Function:
        """Whole-rod F(t, y, yp) -> res as an MX casadi.Function over the loaded kernels.

        Built from the same per-element .casadi kernels (element loops via ``map``), with the
        current parameter vector (including load_scale) embedded. For IDAS cross-checks;
        not for hot loops.
        """
        be = self._casadi or CasadiBackend(self.N)
        N, par = self.N, ca.DM(self._par)
        t = ca.MX.sym("t")
        y, yp = ca.MX.sym("y", self.n), ca.MX.sym("yp", self.n)

        def g(vec, idx):  # (K, m) index array -> (m, K) MX
            return ca.reshape(vec[idx.ravel().tolist()], idx.shape[1], idx.shape[0])

        nargs = be._node_args(self._par, np.zeros(self.n), np.zeros(self.n))
        rn = be._map("rod_node_inertia", N + 1)(g(y, be.n_phi), g(y, be.n_v), g(yp, be.n_phi),
                                                 g(yp, be.n_v), *(ca.DM(a) for a in nargs[4:]),
                                                 par)
        rs = be._map("rod_segment_inertia", N)(g(y, be.s_p), g(y, be.s_om), g(yp, be.s_p),
                                                g(yp, be.s_om), par)
        Q = be._map("rod_segment_forces", N)(g(y, be.n_phi[:-1]), g(y, be.n_phi[1:]),
                                              g(y, be.s_p), g(y, be.n_v[:-1]),
                                              g(y, be.n_v[1:]), g(y, be.s_om), par)
        Q = Q * ca.DM(be._seg_weights(self._par).T)
        # scatter-add via constant selection matrices (sparse, built once)
        res = ca.MX.zeros(self.n)

        def add(idx, vals, sign):
            rows = idx.ravel()
            S = sp.csc_matrix((np.full(rows.size, float(sign)), (rows, np.arange(rows.size))),
                              shape=(self.n, rows.size))
            Sd = ca.DM(ca.Sparsity(self.n, rows.size, S.indptr.tolist(), S.indices.tolist()),
                       S.data)
            return Sd @ ca.vec(vals)

        res = add(be.n6, rn, 1) + add(be.s7, rs, 1) + add(be.seg_rows, Q, -1)
        Tm = be.k["rod_tip_moment"](y[be.s_p[N - 1].tolist()], par)
        res = res + add(be.s_om[N - 1][None], Tm, -1)
        h = float(self._par[L.PARAM_OFFSETS["h"]])
        if N > 1:
            T = be._map("rod_joint_torques", N - 1)(g(y, be.s_p[:-1]), g(y, be.s_p[1:]),
                                                     g(y, be.s_om[:-1]), g(y, be.s_om[1:]), h,
                                                     par)
            res = res + add(be.jnt_rows, T, -1)
        o, z = L.PARAM_OFFSETS, ca.DM.zeros(3)
        if self._par[o["clamp_start"]] > 0.5:
            T = self._casadi_joint(be, ca.DM(self._par[o["p_start"]:o["p_start"] + 4]),
                                   y[be.s_p[0].tolist()], z, y[be.s_om[0].tolist()], h / 2, par)
            res = res + add(be.s_om[0][None], T[3:6], -1)
        if self._par[o["clamp_end"]] > 0.5:
            T = self._casadi_joint(be, y[be.s_p[N - 1].tolist()],
                                   ca.DM(self._par[o["p_end"]:o["p_end"] + 4]),
                                   y[be.s_om[N - 1].tolist()], z, h / 2, par)
            res = res + add(be.s_om[N - 1][None], T[0:3], -1)
        return ca.Function("rod_residual", [t, y, yp], [res], ["t", "y", "yp"], ["res"])

    @staticmethod
    def _casadi_joint(be, *args):
        return be.k["rod_joint_torques"](*args)

    def casadi_energy_function(self) -> ca.Function:
        """E(y) -> (kinetic, elastic, dissipation_rate, external_power) as MX casadi.Function.

        Same kernels as :meth:`diagnostics`; differentiable (e.g. ``jtimes`` for dE/dt).
        """
        be = self._casadi or CasadiBackend(self.N)
        N, par = self.N, ca.DM(self._par)
        y = ca.MX.sym("y", self.n)

        def g(idx):
            return ca.reshape(y[idx.ravel().tolist()], idx.shape[1], idx.shape[0])

        nargs = be._node_args(self._par, np.zeros(self.n), np.zeros(self.n))
        Tn, Pn = be._map("rod_node_kinetic", N + 1)(g(be.n_v), ca.DM(nargs[4]),
                                                     ca.DM(nargs[5]), par)
        free = ca.DM((nargs[6] <= 0.5).astype(float))
        tip = ca.DM((np.arange(1, N + 1) == N).astype(float)[None])
        Ts, Ps = be._map("rod_segment_kinetic", N)(g(be.s_p), g(be.s_om), tip, par)
        Ws, Ds, _, _ = be._map("rod_segment_diagnostics", N)(
            g(be.n_phi[:-1]), g(be.n_phi[1:]), g(be.s_p), g(be.n_v[:-1]), g(be.n_v[1:]),
            g(be.s_om), par)
        kin = ca.sum2(Tn) + ca.sum2(Ts)
        pext = ca.sum2(Pn * free) + ca.sum2(Ps)
        el, dis = ca.sum2(Ws), 2 * ca.sum2(Ds)
        h = float(self._par[L.PARAM_OFFSETS["h"]])
        if N > 1:
            Wj, Dj, _, _ = be._map("rod_joint_diagnostics", N - 1)(
                g(be.s_p[:-1]), g(be.s_p[1:]), g(be.s_om[:-1]), g(be.s_om[1:]), h, par)
            el, dis = el + ca.sum2(Wj), dis + 2 * ca.sum2(Dj)
        o, z = L.PARAM_OFFSETS, ca.DM.zeros(3)
        jd = be.k["rod_joint_diagnostics"]
        if self._par[o["clamp_start"]] > 0.5:
            Wj, Dj, _, _ = jd(ca.DM(self._par[o["p_start"]:o["p_start"] + 4]),
                              y[be.s_p[0].tolist()], z, y[be.s_om[0].tolist()], h / 2, par)
            el, dis = el + Wj, dis + 2 * Dj
        if self._par[o["clamp_end"]] > 0.5:
            Wj, Dj, _, _ = jd(y[be.s_p[N - 1].tolist()],
                              ca.DM(self._par[o["p_end"]:o["p_end"] + 4]),
                              y[be.s_om[N - 1].tolist()], z, h / 2, par)
            el, dis = el + Wj, dis + 2 * Dj
        return ca.Function("rod_energy", [y], [kin, el, dis, pext], ["y"],
                           ["kinetic", "elastic", "dissipation_rate", "external_power"])
