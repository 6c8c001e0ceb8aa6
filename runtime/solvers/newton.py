"""The Newton systems of a BDF step: factor the iteration matrix ``J = dF/dy + cj dF/dy'``
(LAPACK band storage, filled by the problem) and correct the iterate with its solution.

One interface, three implementations by what is available:

* :class:`CondensedSystem`: the kinematic rows eliminated (``native/condensed.py``), the
  condensed matrix block tridiagonal in the rod's cells or banded;
* :class:`BandSystem`: the compiled band LU of the full matrix (``native/band.c``);
* :class:`LapackSystem`: SciPy's LAPACK and NumPy (no C compiler).

``factor(cj)`` factorises J formed at ``cj``; ``correct(res, scale, ewt, ee, yy, ypw,
cj)`` solves ``J d = res``, scales ``d`` by ``scale`` (IDA's 2/(1 + cj/cj_old) after a
change of cj), subtracts it from the correction ``ee`` and the iterate ``yy``, ``cj d``
from ``ypw``, and returns the weighted RMS norm of ``d``; ``res`` is overwritten. The
compiled two fuse all of that in one call (with flush-to-zero, see
``native/__init__.py``); the compiled step loop and the NumPy path call the same code, so
they take the same steps. One exception to "solves J d = res": the condensed system
solves a generalized Maxwell rod's relaxation rows (linear in the internal strains q,
their coefficient of q' is 1) at the current cj, not the factorised one, for the scaled
correction it applies: ``d_q = (r_q - J[q, x] d_x) / (D + cj - cj_f)``, so that those
rows hold to first order after every update (``kv_cond.q_cjf`` in native/condensed.c).
"""

from __future__ import annotations

import math

import numpy as np


class NewtonSystem:
    """Base: the band storage ``ab`` (shape (2 kl + ku + 1, n), Fortran order) that the
    problem fills before :meth:`factor`, and what the compiled step loop needs of it."""

    #: pivots and factor profile (int32), or None (the compiled step loop reads them)
    ipiv: np.ndarray | None = None
    prof: np.ndarray | None = None
    #: address of the condensed system's C struct, or None
    cond_ptr: int | None = None

    def __init__(self, ab: np.ndarray, kl: int, ku: int) -> None:
        self.ab, self.kl, self.ku, self.n = ab, kl, ku, ab.shape[1]

    def factor(self, cj: float) -> int:
        """Factorise ``ab`` (J formed at ``cj``) in place; LAPACK's info (0: regular)."""
        raise NotImplementedError

    def correct(self, res: np.ndarray, scale: float, ewt: np.ndarray, ee: np.ndarray,
                yy: np.ndarray, ypw: np.ndarray, cj: float) -> float:
        """See the module docstring."""
        raise NotImplementedError


class _Addresses:
    """Data addresses of the last arrays seen (``ndarray.ctypes.data`` costs ~3 us; the
    iterate buffers swap with the accepted ones at every step)."""

    def __init__(self) -> None:
        self._cache: dict[int, tuple[np.ndarray, int]] = {}

    def __call__(self, a: np.ndarray) -> int:
        hit = self._cache.get(id(a))
        if hit is not None and hit[0] is a:
            return hit[1]
        if len(self._cache) > 16:
            self._cache.clear()
        ptr = a.ctypes.data
        self._cache[id(a)] = (a, ptr)
        return ptr


class LapackSystem(NewtonSystem):
    """SciPy's ``dgbtrf``/``dgbtrs`` (imported on use: scipy.linalg costs ~0.2 s of
    import) and the update in NumPy."""

    def __init__(self, ab: np.ndarray, kl: int, ku: int) -> None:
        super().__init__(ab, kl, ku)
        self._tmp = np.empty(self.n)
        self._piv: np.ndarray | None = None

    def factor(self, cj: float) -> int:
        from scipy.linalg.lapack import dgbtrf

        self._piv = None  # free the old pivots first (dgbtrf allocates new ones)
        _, self._piv, info = dgbtrf(self.ab, self.kl, self.ku, overwrite_ab=1)
        return int(info)

    def correct(self, res, scale, ewt, ee, yy, ypw, cj) -> float:
        from scipy.linalg.lapack import dgbtrs

        dgbtrs(self.ab, self.kl, self.ku, res, self._piv, overwrite_b=1)
        if scale != 1.0:
            res *= scale
        tmp = self._tmp
        np.multiply(res, ewt, out=tmp)
        delnrm = math.sqrt(float(np.dot(tmp, tmp)) * (1.0 / self.n))
        ee -= res
        yy -= res
        np.multiply(res, cj, out=tmp)
        ypw -= tmp
        return delnrm


class BandSystem(NewtonSystem):
    """The compiled band LU (``kv_gbtrf``: LAPACK's dgbtf2 with a factor profile) and the
    fused solve and update (``kv_newton``)."""

    def __init__(self, ab: np.ndarray, kl: int, ku: int, lib) -> None:
        super().__init__(ab, kl, ku)
        self._lib = lib
        self.ipiv = np.zeros(max(self.n, 1), dtype=np.int32)
        self.prof = np.zeros(2 * max(self.n, 1), dtype=np.int32)
        self._p = _Addresses()

    def factor(self, cj: float) -> int:
        p = self._p
        return int(self._lib.kv_gbtrf(self.n, self.kl, self.ku, p(self.ab), self.ab.shape[0],
                                      p(self.ipiv), p(self.prof)))

    def correct(self, res, scale, ewt, ee, yy, ypw, cj) -> float:
        p = self._p
        return self._lib.kv_newton(self.n, self.kl, self.ku, p(self.ab), self.ab.shape[0],
                                   p(self.ipiv), p(self.prof), p(res), scale, p(ewt), p(ee),
                                   p(yy), p(ypw), cj)


class CondensedSystem(NewtonSystem):
    """The condensed systems (``native/condensed.py``): ``factor`` condenses and
    factorises (J stays in ``ab``: the solves read it), ``kv_cond_newton`` solves and
    updates."""

    def __init__(self, ab: np.ndarray, kl: int, ku: int, lib, cond) -> None:
        super().__init__(ab, kl, ku)
        self._lib, self.cond = lib, cond
        self.cond_ptr = cond.ptr
        self.ipiv = np.zeros(max(self.n, 1), dtype=np.int32)     # unused, kept for C
        self.prof = np.zeros(2 * max(self.n, 1), dtype=np.int32)
        self._p = _Addresses()

    def factor(self, cj: float) -> int:
        return int(self.cond.factor(self.ab, cj))

    def correct(self, res, scale, ewt, ee, yy, ypw, cj) -> float:
        p = self._p
        return self._lib.kv_cond_newton(self.cond_ptr, p(self.ab), p(res), scale, p(ewt),
                                        p(ee), p(yy), p(ypw), cj)


class BlocksSystem(NewtonSystem):
    """A problem's own coupled band blocks (``native/blocks.py``: an assembly of rods, each
    a block, the joints the couplings): :meth:`setup` has the problem write its Jacobian
    into them (``problem.system_jacobian``) and factorises; the compiled step loop does
    the same through ``blocks_ptr`` and the problem's compiled system Jacobian."""

    def __init__(self, problem) -> None:
        self.problem = problem
        self.blocks = problem.blocks
        self.blocks_ptr = self.blocks.ptr
        n = self.blocks.n
        super().__init__(np.zeros((1, max(n, 1)), order="F"), 0, 0)
        self.ipiv = np.zeros(max(n, 1), dtype=np.int32)       # unused, kept for C
        self.prof = np.zeros(2 * max(n, 1), dtype=np.int32)

    def setup(self, t: float, y: np.ndarray, yp: np.ndarray, cj: float) -> int:
        """J at (t, y, y') into the blocks, factorised; 0, or > 0 when singular."""
        self.problem.system_jacobian(t, y, yp, cj)
        return self.blocks.factor()

    def factor(self, cj: float) -> int:
        raise RuntimeError("BlocksSystem: the Jacobian is the problem's (use setup)")

    def correct(self, res, scale, ewt, ee, yy, ypw, cj) -> float:
        return self.blocks.correct(res, scale, ewt, ee, yy, ypw, cj)


def newton_system(problem, ab: np.ndarray, kl: int, ku: int, lib,
                  condense: bool = True) -> NewtonSystem:
    """The best Newton system available for ``problem``: its own (``newton_system()``, an
    assembly's coupled blocks), condensed when the problem names its kinematic blocks
    (``condensation_blocks()``) and the compiled library ``lib`` is there, else the
    compiled band LU, else LAPACK."""
    own = getattr(problem, "newton_system", None)
    if own is not None:
        return own()
    if lib is None:
        return LapackSystem(ab, kl, ku)
    if condense:
        from .native.condensed import CondensedNewton

        cond = CondensedNewton.build(problem, ab.shape[1], kl, ku, ab.shape[0])
        if cond is not None:
            return CondensedSystem(ab, kl, ku, lib, cond)
    return BandSystem(ab, kl, ku, lib)
