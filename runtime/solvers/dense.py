"""The interpolant of an accepted BDF step (IDA's ``IDAGetDky``): y and y' anywhere in the
step from the history ``phi`` and the step sizes ``psi``, at many times in one pass
(``kv_interp`` of the compiled helpers, or NumPy)."""

from __future__ import annotations

import numpy as np


def _interp_coefficients(
    t: np.ndarray, tn: float, psi: np.ndarray, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """IDA's interpolation weights: ``y(t) = sum c_j phi_j``, ``y'(t) = sum d_j phi_j``.

    ``t`` has shape (m,); returns ``c`` of shape (k+1, m) and ``d`` of shape (k+1, m)
    (``d[0] = 0``).
    """
    if t.size == 1:  # the common case (one output time in a step): scalar arithmetic
        delt = float(t[0]) - tn
        cl, dl = [1.0], [0.0]
        cs, ds = 1.0, 0.0
        gs = delt / psi[0]
        for j in range(1, k + 1):
            ds = ds * gs + cs / psi[j - 1]
            cs = cs * gs
            if j < k:
                gs = (delt + psi[j - 1]) / psi[j]
            cl.append(cs)
            dl.append(ds)
        return np.array(cl).reshape(k + 1, 1), np.array(dl).reshape(k + 1, 1)
    delt = t - tn
    c = np.empty((k + 1, t.size))
    d = np.zeros((k + 1, t.size))
    cc = np.ones_like(delt)
    dd = np.zeros_like(delt)
    gam = delt / psi[0]
    c[0] = 1.0
    for j in range(1, k + 1):
        dd = dd * gam + cc / psi[j - 1]
        cc = cc * gam
        gam = (delt + psi[j - 1]) / psi[j] if j < k else gam
        c[j] = cc
        d[j] = dd
    return c, d


class BDFDenseOutput:
    """The BDF interpolating polynomial of one step, valid on ``[t_old, t]``.

    Calling it gives ``y(t)`` with shape (n,) for scalar ``t`` or (n, m) for an array;
    ``derivative(t)`` gives ``y'(t)`` in the same shapes. ``sens``: the interpolant of the
    same step's forward sensitivities (their k n values stacked), or None.
    """

    sens: BDFDenseOutput | None = None

    def __init__(self, t_old: float, t: float, phi: np.ndarray, psi: np.ndarray,
                 clib=None) -> None:
        self.t_old = t_old
        self.t = t
        self.t_min, self.t_max = min(t_old, t), max(t_old, t)
        self._phi = phi  # (k+1, n), C order
        self._psi = psi  # (k,) at least
        self._k = phi.shape[0] - 1
        self._c = clib   # compiled helpers (kv_interp) or None

    def _eval(self, t: float | np.ndarray, deriv: bool) -> np.ndarray:
        ta = np.atleast_1d(np.asarray(t, dtype=float))
        c, d = _interp_coefficients(ta, self.t, self._psi, self._k)
        out = ((d if deriv else c).T @ self._phi).T
        return out[:, 0] if np.ndim(t) == 0 else out

    def values(self, t: np.ndarray, out_y: np.ndarray | None = None,
               out_yp: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(y(t), y'(t))`` for times ``t`` of shape (m,), each of shape (m, n) (one row
        per time; note the order), written into ``out_y``/``out_yp`` if given."""
        ta = np.ascontiguousarray(t, dtype=float)
        phi = self._phi  # (k+1, n), C order: c.T @ phi runs over contiguous rows
        if self._c is not None and phi.flags.c_contiguous:
            m, n = ta.size, phi.shape[1]
            y = out_y if out_y is not None else np.empty((m, n))
            yp = out_yp if out_yp is not None else np.empty((m, n))
            psi = np.ascontiguousarray(self._psi, dtype=float)
            self._c.kv_interp(self._k, n, m, self.t, psi.ctypes.data, phi.ctypes.data,
                              ta.ctypes.data, y.ctypes.data, yp.ctypes.data)
            return y, yp
        c, d = _interp_coefficients(ta, self.t, self._psi, self._k)
        return np.matmul(c.T, phi, out=out_y), np.matmul(d.T, phi, out=out_yp)

    def __call__(self, t: float | np.ndarray) -> np.ndarray:
        return self._eval(t, False)

    def derivative(self, t: float | np.ndarray) -> np.ndarray:
        return self._eval(t, True)
