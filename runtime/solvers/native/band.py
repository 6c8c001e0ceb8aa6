"""The LU factors of a band matrix and its solves (``kv_gbtrf``/``kv_gbtrs`` of band.c,
or SciPy's LAPACK without the compiled library)."""

from __future__ import annotations

from .loader import load


class BandLU:
    """The LU factors of a band matrix in LAPACK storage ``ab`` (overwritten), by the
    compiled helpers or else SciPy's LAPACK (imported only then); ``info`` is LAPACK's
    (> 0: singular, column ``info`` 1-based), :meth:`solve` returns a new array."""

    def __init__(self, ab, kl: int, ku: int) -> None:
        import numpy as np

        self.ab, self.kl, self.ku = ab, kl, ku
        self._lib = load()
        n = ab.shape[1]
        if self._lib is None:
            from scipy.linalg.lapack import dgbtrf

            _, self._ipiv, info = dgbtrf(ab, kl, ku, overwrite_ab=1)
            self.info = int(info)
            return
        if not (ab.flags.f_contiguous and ab.dtype == np.float64):
            raise ValueError("BandLU: ab must be a Fortran-ordered float64 array")
        self._ipiv = np.zeros(max(n, 1), dtype=np.int32)
        self._prof = np.zeros(2 * max(n, 1), dtype=np.int32)
        self.info = int(self._lib.kv_gbtrf(n, kl, ku, ab.ctypes.data, ab.shape[0],
                                           self._ipiv.ctypes.data, self._prof.ctypes.data))

    def solve(self, b):
        """``A^-1 b`` (b unchanged)."""
        import numpy as np

        if self.info != 0:
            raise ValueError(f"BandLU.solve: the matrix is singular (info {self.info})")
        if self._lib is None:
            from scipy.linalg.lapack import dgbtrs

            return dgbtrs(self.ab, self.kl, self.ku, np.asarray(b, dtype=float),
                          self._ipiv)[0]
        x = np.array(b, dtype=float)
        self._lib.kv_gbtrs(self.ab.shape[1], self.kl, self.ku, self.ab.ctypes.data,
                           self.ab.shape[0], self._ipiv.ctypes.data, self._prof.ctypes.data,
                           x.ctypes.data)
        return x


def band_solve(ab, kl: int, ku: int, b):
    """``(x, info)`` of ``A x = b`` for A in band storage ``ab`` (overwritten by its LU;
    x is a new array, b unchanged; info > 0: singular, x is then a copy of b)."""
    import numpy as np

    lu = BandLU(ab, kl, ku)
    return (lu.solve(b) if lu.info == 0 else np.array(b, dtype=float)), lu.info
