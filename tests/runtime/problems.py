"""Test problems implementing the runtime protocols, with analytic references."""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.sparse

from runtime.solvers.protocols import DenseProblem, dense_to_band


class KVChain:
    """Chain of M point masses joined by Kelvin-Voigt springs, in first-order IDA form.

    Mass 0 is tied to a wall, mass M-1 is free.  Unknowns interleaved per mass:
    ``y = [x_0, v_0, x_1, v_1, ...]`` (m, m/s), n = 2M.  Residual
    ``F_x,i = x_i' - v_i``, ``F_v,i = m_i v_i' - (T_{i+1} - T_i)`` with spring tension
    ``T_i = k (x_i - x_{i-1}) + c (v_i - v_{i-1})`` (``x_{-1} = 0``, ``T_M = 0``).
    Light masses (every ``light_every``-th) make the system stiff (eigenvalues near
    ``-c / m_light``) while the lowest modes stay lightly damped.
    ``band`` pads the declared bandwidth (kl = ku = band >= 3) to mimic a wider band.
    """

    def __init__(
        self,
        M: int = 20,
        k: float = 2000.0,
        c: float = 56.0,
        m_light: float = 1e-4,
        light_every: int = 2,
        band: int = 3,
    ) -> None:
        self.M = M
        self.n = 2 * M
        self.kl = self.ku = max(3, band)
        self.differential = np.ones(self.n, dtype=bool)
        self.k, self.c = k, c
        self.m = np.ones(M)
        self.m[light_every - 1 :: light_every] = m_light
        self._u = np.empty(M)
        self._w = np.empty(M)
        self._T = np.zeros(M + 1)
        # Linear: F = E y' - K y, K assembled sparse (COO triplets).
        rows, cols, vals = [], [], []
        for i in range(M):
            rows.append(2 * i)
            cols.append(2 * i + 1)
            vals.append(1.0)
            pairs = [(i, -1.0), (i - 1, 1.0)]  # spring i pulls mass i back
            if i + 1 < M:
                pairs += [(i + 1, 1.0), (i, -1.0)]  # spring i+1 pulls it forward
            for j, sgn in pairs:
                if j >= 0:
                    rows += [2 * i + 1, 2 * i + 1]
                    cols += [2 * j, 2 * j + 1]
                    vals += [sgn * k, sgn * c]
        self.K = scipy.sparse.csr_matrix((vals, (rows, cols)), shape=(self.n, self.n))
        self.E = np.ones(self.n)
        self.E[1::2] = self.m
        self._ediag = np.empty(self.n)
        kl = ku = self.kl
        self._negK_ab = np.zeros((2 * kl + ku + 1, self.n), order="F")
        coo = self.K.tocoo()
        np.add.at(self._negK_ab, (kl + ku + coo.row - coo.col, coo.col), -coo.data)
        self._diag_row = kl + ku

    @property
    def A(self) -> np.ndarray:
        """Dense system matrix of ``y' = A y`` (small chains only)."""
        return self.K.toarray() / self.E[:, None]

    def rhs(self, y: np.ndarray) -> np.ndarray:
        """``y' = E^-1 K y`` (a consistent initial derivative)."""
        return (self.K @ y) / self.E

    def residual(self, t, y, yp, out):
        x, v = y[0::2], y[1::2]
        u, w, T = self._u, self._w, self._T
        np.multiply(x, self.k, out=u)
        np.multiply(v, self.c, out=w)
        u += w
        T[0] = u[0]
        np.subtract(u[1:], u[:-1], out=T[1:-1])
        np.subtract(yp[0::2], v, out=out[0::2])
        np.multiply(self.m, yp[1::2], out=out[1::2])
        np.subtract(T[1:], T[:-1], out=w)
        out[1::2] -= w

    def jacobian_band(self, t, y, yp, cj, out_ab):
        kl = self.kl
        out_ab[kl:] = self._negK_ab[kl:]
        np.multiply(self.E, cj, out=self._ediag)
        out_ab[self._diag_row] += self._ediag

    def initial(self) -> np.ndarray:
        """Smooth initial displacement (first fixed-free shape), zero velocity."""
        y0 = np.zeros(self.n)
        s = (np.arange(self.M) + 1.0) / self.M
        y0[0::2] = 0.1 * np.sin(0.5 * np.pi * s)
        return y0

    def exact(self, t: np.ndarray, y0: np.ndarray) -> np.ndarray:
        """Exact solution (n, len(t)) by the matrix exponential."""
        A = self.A
        return np.column_stack([scipy.linalg.expm(A * ti) @ y0 for ti in np.atleast_1d(t)])


def semi_explicit_dae(y1_0: float = 2.0) -> tuple[DenseProblem, callable]:
    """Index-1 DAE ``y1' = -y1 + z``, ``0 = z^3 + z - (cos^3 t + cos t)``.

    Exact: ``z = cos t``, ``y1 = (cos t + sin t)/2 + (y1(0) - 1/2) e^{-t}``.
    Returns the problem and ``exact(t) -> (y, yp)`` arrays of shape (2, m).
    """

    def f(t, y, yp):
        y1, z = y
        return np.array([yp[0] + y1 - z, z**3 + z - (np.cos(t) ** 3 + np.cos(t))])

    def jy(t, y, yp):
        return np.array([[1.0, -1.0], [0.0, 3 * y[1] ** 2 + 1.0]])

    def jyp(t, y, yp):
        return np.array([[1.0, 0.0], [0.0, 0.0]])

    prob = DenseProblem(f, jy, jyp, 2, differential=np.array([True, False]))

    def exact(t):
        t = np.asarray(t, dtype=float)
        a = y1_0 - 0.5
        y = np.array([(np.cos(t) + np.sin(t)) / 2 + a * np.exp(-t), np.cos(t)])
        yp = np.array([(-np.sin(t) + np.cos(t)) / 2 - a * np.exp(-t), -np.sin(t)])
        return y, yp

    return prob, exact


class Oscillator:
    """Harmonic oscillator ``x' = v``, ``v' = -omega^2 x`` (band kl = ku = 1)."""

    def __init__(self, omega: float = 2.0) -> None:
        self.n, self.kl, self.ku = 2, 1, 1
        self.differential = np.ones(2, dtype=bool)
        self.omega = omega

    def residual(self, t, y, yp, out):
        out[0] = yp[0] - y[1]
        out[1] = yp[1] + self.omega**2 * y[0]

    def jacobian_band(self, t, y, yp, cj, out_ab):
        J = np.array([[cj, -1.0], [self.omega**2, cj]])
        dense_to_band(J, 1, 1, out_ab)


class Scalar:
    """Scalar ODE ``y' = f(t, y)`` given ``f`` and ``df/dy``."""

    def __init__(self, f, dfdy) -> None:
        self.n, self.kl, self.ku = 1, 0, 0
        self.differential = np.ones(1, dtype=bool)
        self.f, self.dfdy = f, dfdy

    def residual(self, t, y, yp, out):
        out[0] = yp[0] - self.f(t, y[0])

    def jacobian_band(self, t, y, yp, cj, out_ab):
        out_ab[0, 0] = cj - self.dfdy(t, y[0])


# ---------------------------------------------------------------------------- statics
class SpringChainStatic:
    """Chain of n nonlinear springs ``f(s) = k s + k3 s^3`` fixed at a wall, tip load P.

    Unknowns: positions x_1..x_n of the joints (reduced = full; retract is addition).
    Exact equilibrium: every spring carries P, so ``x_i = i s*`` with ``f(s*) = P``.
    """

    def __init__(self, n: int = 10, k: float = 1.0, k3: float = 5.0, P: float = 20.0) -> None:
        self.n_static = n
        self.kl_static = self.ku_static = 1
        self.k, self.k3, self.P = k, k3, P
        self.load_scale = 1.0

    def _s(self, y):
        return np.diff(np.concatenate(([0.0], y)))

    def static_residual(self, y, out):
        s = self._s(y)
        f = self.k * s + self.k3 * s**3
        out[:] = f
        out[:-1] -= f[1:]
        out[-1] -= self.load_scale * self.P

    def static_jacobian_band(self, y, out_ab):
        s = self._s(y)
        d = self.k + 3 * self.k3 * s**2  # spring stiffnesses
        n = self.n_static
        J = np.zeros((n, n))
        idx = np.arange(n)
        J[idx, idx] = d
        J[idx[:-1], idx[:-1]] += d[1:]
        J[idx[:-1], idx[1:]] = -d[1:]
        J[idx[1:], idx[:-1]] = -d[1:]
        dense_to_band(J, 1, 1, out_ab)

    def static_retract(self, y, dx):
        return y + dx

    def exact(self) -> np.ndarray:
        roots = np.roots([self.k3, 0.0, self.k, -self.load_scale * self.P])
        s = float(np.real(roots[np.argmin(np.abs(roots.imag))]))
        return s * np.arange(1, self.n_static + 1)


class PlanarElastica:
    """Discrete inextensible planar cantilever in angle coordinates, dead tip load.

    Segment angles theta_1..theta_n (rad), clamp theta_0 = 0, length L (m), bending
    stiffness EI (N m^2), transverse tip force P (N).  Potential
    ``sum k_i/2 (theta_i - theta_{i-1})^2 - load_scale P h sum sin(theta_i)`` with
    ``k_i = EI/h`` and a half cell ``k_1 = 2 EI/h`` at the clamp.
    """

    def __init__(self, n: int = 40, L: float = 1.0, EI: float = 1.0, P: float = 3.0) -> None:
        self.n_static = n
        self.kl_static = self.ku_static = 1
        self.L, self.EI, self.P = L, EI, P
        self.h = L / n
        self.load_scale = 1.0

    def _kb(self) -> np.ndarray:
        # Half-length first cell: theta_1 sits at s = h/2, the clamp at s = 0 (O(h^2)).
        kb = np.full(self.n_static, self.EI / self.h)
        kb[0] *= 2.0
        return kb

    def static_residual(self, y, out):
        kb = self._kb()
        m = kb * np.diff(np.concatenate(([0.0], y)))  # bending moments at cell joints
        out[:] = m
        out[:-1] -= m[1:]
        out -= self.load_scale * self.P * self.h * np.cos(y)

    def static_jacobian_band(self, y, out_ab):
        kb = self._kb()
        diag = kb.copy()
        diag[:-1] += kb[1:]
        diag += self.load_scale * self.P * self.h * np.sin(y)
        out_ab[2, :] = diag  # row kl + ku for kl = ku = 1
        out_ab[1, 1:] = -kb[1:]  # upper diagonal J[i, i+1] at column i+1
        out_ab[3, :-1] = -kb[1:]  # lower diagonal J[i+1, i] at column i

    def static_retract(self, y, dx):
        return y + dx

    def tip(self, y) -> tuple[float, float]:
        return float(self.h * np.sum(np.cos(y))), float(self.h * np.sum(np.sin(y)))


class AtanStatic:
    """Independent components ``R_i = atan(x_i - load_scale * c_i)``: full Newton from
    x = 0 overshoots and diverges for ``|c_i| > 1.39``; damped Newton converges."""

    def __init__(self, c) -> None:
        self.c = np.asarray(c, dtype=float)
        self.n_static = self.c.size
        self.kl_static = self.ku_static = 0
        self.load_scale = 1.0

    def static_residual(self, y, out):
        out[:] = np.arctan(y - self.load_scale * self.c)

    def static_jacobian_band(self, y, out_ab):
        out_ab[0, :] = 1.0 / (1.0 + (y - self.load_scale * self.c) ** 2)

    def static_retract(self, y, dx):
        return y + dx


class FoldStatic:
    """``R = x^2 - 2 + 3 load_scale`` from x = sqrt(2): the root disappears at 2/3."""

    n_static = 1
    kl_static = ku_static = 0

    def __init__(self) -> None:
        self.load_scale = 0.0

    def static_residual(self, y, out):
        out[0] = y[0] ** 2 - 2.0 + 3.0 * self.load_scale

    def static_jacobian_band(self, y, out_ab):
        out_ab[0, 0] = 2.0 * y[0]

    def static_retract(self, y, dx):
        return y + dx


class Robertson:
    """Robertson's chemical kinetics as an index-1 DAE (the IDA example ``idaRoberts``):
    ``y1' = -0.04 y1 + 1e4 y2 y3``, ``y2' = 0.04 y1 - 1e4 y2 y3 - 3e7 y2^2``,
    ``0 = y1 + y2 + y3 - 1``."""

    def __init__(self) -> None:
        self.n, self.kl, self.ku = 3, 2, 2
        self.differential = np.array([True, True, False])

    def residual(self, t, y, yp, out):
        y1, y2, y3 = y
        out[0] = yp[0] + 0.04 * y1 - 1e4 * y2 * y3
        out[1] = yp[1] - 0.04 * y1 + 1e4 * y2 * y3 + 3e7 * y2 * y2
        out[2] = y1 + y2 + y3 - 1.0

    def jacobian_band(self, t, y, yp, cj, out_ab):
        y1, y2, y3 = y
        J = np.array(
            [
                [cj + 0.04, -1e4 * y3, -1e4 * y2],
                [-0.04, cj + 1e4 * y3 + 6e7 * y2, 1e4 * y2],
                [1.0, 1.0, 1.0],
            ]
        )
        dense_to_band(J, 2, 2, out_ab)
