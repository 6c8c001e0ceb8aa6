"""Problem protocols seen by the integrator and the static solver, plus small adapters.

The integrator works on IDA's implicit form ``F(t, y, y') = 0`` and needs the iteration
matrix ``J = dF/dy + cj dF/dy'`` in LAPACK general-band storage (as used by ``dgbtrf``):
an array ``ab`` of shape ``(2*kl + ku + 1, n)``, Fortran order, with element ``J[i, j]``
at ``ab[kl + ku + i - j, j]``.  The top ``kl`` rows are workspace for the LU factors.
Callers zero ``ab`` before asking a problem to fill it, so a problem only writes the
entries inside its band.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = [
    "ResidualProblem",
    "StaticProblem",
    "DenseProblem",
    "band_storage",
    "dense_to_band",
    "band_to_dense",
]


@runtime_checkable
class ResidualProblem(Protocol):
    """A DAE/ODE in IDA form ``F(t, y, y') = 0`` with a banded iteration matrix.

    Attributes
    ----------
    n : number of unknowns.
    kl, ku : lower / upper bandwidth of ``dF/dy + cj dF/dy'``.
    differential : bool array (n,); False marks algebraic components (zero dF/dy' column).
    """

    n: int
    kl: int
    ku: int
    differential: np.ndarray

    def residual(self, t: float, y: np.ndarray, yp: np.ndarray, out: np.ndarray) -> None:
        """Write ``F(t, y, y')`` (shape (n,)) into ``out``."""
        ...

    def jacobian_band(
        self, t: float, y: np.ndarray, yp: np.ndarray, cj: float, out_ab: np.ndarray
    ) -> None:
        """Write ``dF/dy + cj dF/dy'`` into the (pre-zeroed) band array ``out_ab``."""
        ...


@runtime_checkable
class StaticProblem(Protocol):
    """Equilibrium ``R(y; load_scale) = 0`` in reduced coordinates (increments ``dx``).

    ``y`` is the full state (whatever the problem uses, e.g. with unit quaternions);
    residual, Jacobian and increments live in the reduced space of size ``n_static``.
    """

    n_static: int
    kl_static: int
    ku_static: int
    load_scale: float

    def static_residual(self, y: np.ndarray, out: np.ndarray) -> None:
        """Write the residual (shape (n_static,)) at state ``y`` into ``out``."""
        ...

    def static_jacobian_band(self, y: np.ndarray, out_ab: np.ndarray) -> None:
        """Write ``dR/dx`` at ``y`` into the (pre-zeroed) band array ``out_ab``."""
        ...

    def static_retract(self, y: np.ndarray, dx: np.ndarray) -> np.ndarray:
        """Return a new full state from ``y`` moved by the reduced increment ``dx``."""
        ...

    # optional: ``constrain(y) -> y`` moves prescribed unknowns (held nodes) to their
    # targets at the current load factor; solve_static calls it after every change of it
    # optional: ``static_newton_trial(y, res) -> (factor, dx, y_try) | None``: a full
    # Newton trial in one call (res: the residual at y, overwritten by that at y_try), the
    # same bits as the steps above one after another; None where it cannot


def band_storage(n: int, kl: int, ku: int) -> np.ndarray:
    """Return a zeroed Fortran-ordered array of shape (2*kl+ku+1, n) for ``dgbtrf``."""
    return np.zeros((2 * kl + ku + 1, n), order="F")


def dense_to_band(a: np.ndarray, kl: int, ku: int, out_ab: np.ndarray) -> None:
    """Copy the band of the dense (n, n) matrix ``a`` into ``dgbtrf`` storage ``out_ab``."""
    n = a.shape[0]
    for d in range(-kl, ku + 1):  # d = j - i
        row = kl + ku - d
        if d >= 0:
            out_ab[row, d:] = np.diagonal(a, d)
        else:
            out_ab[row, : n + d] = np.diagonal(a, d)


def band_to_dense(ab: np.ndarray, kl: int, ku: int) -> np.ndarray:
    """Return the dense (n, n) matrix stored in rows ``kl:`` of ``dgbtrf`` storage ``ab``."""
    n = ab.shape[1]
    a = np.zeros((n, n))
    for d in range(-kl, ku + 1):
        row = kl + ku - d
        idx = np.arange(max(0, -d), min(n, n - d))
        a[idx, idx + d] = ab[row, idx + d]
    return a


class DenseProblem:
    """Adapter: a small residual problem given by callables with dense Jacobians.

    Parameters
    ----------
    residual : ``f(t, y, yp) -> (n,)`` array.
    jac_y, jac_yp : ``(t, y, yp) -> (n, n)`` arrays ``dF/dy`` and ``dF/dy'``.
    n : number of unknowns.
    differential : bool array (n,), False for algebraic components; default all True.
    kl, ku : bandwidths; default ``n - 1`` (full).
    """

    def __init__(
        self,
        residual: Callable[[float, np.ndarray, np.ndarray], np.ndarray],
        jac_y: Callable[[float, np.ndarray, np.ndarray], np.ndarray],
        jac_yp: Callable[[float, np.ndarray, np.ndarray], np.ndarray],
        n: int,
        differential: np.ndarray | None = None,
        kl: int | None = None,
        ku: int | None = None,
    ) -> None:
        self.n = int(n)
        self.kl = self.n - 1 if kl is None else int(kl)
        self.ku = self.n - 1 if ku is None else int(ku)
        self.differential = (
            np.ones(self.n, dtype=bool) if differential is None else np.asarray(differential, bool)
        )
        self._f = residual
        self._jy = jac_y
        self._jyp = jac_yp

    def residual(self, t: float, y: np.ndarray, yp: np.ndarray, out: np.ndarray) -> None:
        out[:] = self._f(t, y, yp)

    def jacobian_band(
        self, t: float, y: np.ndarray, yp: np.ndarray, cj: float, out_ab: np.ndarray
    ) -> None:
        a = np.asarray(self._jy(t, y, yp), dtype=float) + cj * np.asarray(
            self._jyp(t, y, yp), dtype=float
        )
        dense_to_band(a, self.kl, self.ku, out_ab)


#: most values per state a problem's compiled energies may return (KV_MAXEN of the step
#: loop: an assembly's joints and supports add six and three each)
MAX_ENERGIES = 2048


class CKernels:
    """Compiled functions of a problem for the C step loop: addresses of the residual, the
    banded Jacobian and (optional, 0 if none) the energies (signatures of
    ``kvrod_residual``, ``kvrod_jacobian_band``, ``kvrod_energies`` in
    ``runtime/model/native/rod_assembly.h``) and of their first argument ``ctx``; ``drive(t)``
    (optional) makes the functions valid at time t and returns the interval ``[lo, hi)``
    on which they then stay valid; ``keep`` holds whatever must outlive the solver.

    ``jacobian_cells`` (optional, 0 if none): the Jacobian element by element
    (``kvrod_jacobian_band_cells``), element i being cell i of the problem's
    ``condensation_cells()``; with it the step loop factors the condensed Newton
    matrix cell by cell right behind the Jacobian's sweep.

    ``drive_constant``: the loads do not change with t (``drive`` returns an unbounded
    interval); the step loop then drives once from Python before each run and never
    calls back into Python for it.

    ``n_energies``: values per state the energies return (at least 5: T, W, 2D, P_ext,
    P_bc; the extras, e.g. the supports' reactions, are sampled with the outputs).

    ``system_jacobian`` (optional, 0 if none): the Jacobian of a system of coupled band
    blocks (an assembly: ``kvsys_jacobian``), for a problem whose Newton system is its own
    coupled blocks.

    ``max_step`` (optional, 0 if none): ``double f(ctx, t, y, yp)``, the largest next step
    the state allows (contact: ``kvrod_max_step``); the loop applies it after every
    accepted step as the BDF's ``_state_max_step`` does.

    ``error_weights`` (optional, 0 if none): ``int f(ctx, y, rtol, atol, w)``, the state's
    change of the error test's weights ``w = 1/(rtol |y| + atol)`` in place (contact:
    ``kvrod_error_weights``); the loop applies it after every accepted step as the BDF's
    ``_state_error_weights`` does; a negative return fails the run.

    ``audit_energies`` (optional, 0 if none): the energies' signature, filling only 2D
    and the powers (values 2, 3, 4 of a state) bit for bit as ``energies`` does
    (``kvrod_audit_powers``): the energy audit's quadrature points need no more.

    ``energies_reentrant``: the energies read nothing that the residual or the Jacobian
    write (a rod without contact: its kernels take the rod's struct read-only), so the
    step loop may evaluate them on a second thread while the steps go on
    (``CoreLink.enable_audit``).

    ``energies_read_rates`` (default True): the energies read y' (a rod with coupled
    sections); False lets the step loop interpolate the audit's and the samples' states
    without y'.

    ``jacobian_cells_relaxed`` (optional, None if none): ``(function, set_need)`` for a
    condensation that eliminates relaxation blocks by their declared structure:
    ``function`` is ``jacobian_cells`` forming only the relaxation rows and columns that
    ``set_need(need)`` marks (``need``: uint8 per state index, bit 0 the column, bit 1 the
    row in full, else only the diagonal entry; ``kvrod_jacobian_band_cells_relaxed``),
    every entry it forms bit for bit as ``jacobian_cells``."""

    def __init__(self, residual: int, jacobian: int, energies: int, ctx: int,
                 drive=None, keep: Any = None, jacobian_cells: int = 0,
                 drive_constant: bool = False, n_energies: int = 5) -> None:
        self.residual, self.jacobian, self.energies, self.ctx = residual, jacobian, energies, ctx
        if not 5 <= n_energies <= MAX_ENERGIES:
            raise ValueError(f"n_energies = {n_energies}: 5 ... {MAX_ENERGIES} values per "
                             "state")
        self.n_energies = int(n_energies)
        self.jacobian_cells = jacobian_cells
        self.drive_constant = drive_constant
        self.drive = drive
        self.keep = keep
        self.system_jacobian = 0
        self.max_step = 0
        self.error_weights = 0
        self.audit_energies = 0
        self.energies_reentrant = False
        self.energies_read_rates = True
        self.jacobian_cells_relaxed = None
