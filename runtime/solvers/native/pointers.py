"""Data addresses of NumPy arrays for the compiled code's ctypes calls (the rod's kernels,
the static Newton's work in statics.c)."""

from __future__ import annotations

import numpy as np


def data_address(a: np.ndarray, n: int, fortran: bool = False) -> int:
    """Data address of a contiguous (C, or Fortran if asked) float64 array of size >= n."""
    ok = isinstance(a, np.ndarray) and a.dtype == np.float64 and a.size >= n and (
        a.flags.f_contiguous if fortran else a.flags.c_contiguous)
    if not ok:
        order = "Fortran" if fortran else "C"
        raise TypeError(f"expected a {order}-contiguous float64 numpy array of size >= {n}")
    return a.ctypes.data


class PointerCache:
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
        ptr = data_address(a, n, fortran)
        self._arrays.insert(0, a)
        self._ptrs.insert(0, ptr)
        del self._arrays[self._size:], self._ptrs[self._size:]
        return ptr


def function_address(fn) -> int:
    """Address of a ctypes function (a library's symbol or a callback) as an int, for the
    C structs that call it."""
    import ctypes

    return ctypes.cast(fn, ctypes.c_void_p).value
