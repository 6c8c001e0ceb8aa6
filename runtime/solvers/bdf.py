"""Variable-order, variable-step BDF for ``F(t, y, y') = 0`` in the form of SUNDIALS IDA.

The method is the fixed-leading-coefficient BDF of Brenan, Campbell and Petzold as
implemented in IDA (see IDA's theory guide and ``ida.c``): the history is kept as
modified divided differences ``phi[0..k]`` scaled to the step (``phi[j] ~ h^j y^(j)``),
the predictor is the interpolating polynomial through the last ``k + 1`` points, the
corrector solves ``F(t_n, y_pred + e, y'_pred + cj e) = 0`` for the correction ``e``
by simplified Newton with the iteration matrix ``J = dF/dy + cj dF/dy'`` (cj = alpha_s/h),
factorised by LAPACK's banded LU and reused across iterations and steps.  The local
error test, the order and step selection, and the failure handling follow IDA's
heuristics and constants.

Units: ``t`` and ``h`` are in the problem's time unit (s for the rod); ``y`` is (n,).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from runtime.errors import ParameterError
from runtime.solvers.protocols import ResidualProblem, band_storage

from .dense import BDFDenseOutput
from .native import loader as _native
from .native.step_loop import (
    CALLBACK,
    FAIL_CONV,
    FAIL_ERR,
    FAIL_FIXED,
    FAIL_HMIN,
    FAIL_STALL,
    MAXSTEPS,
    NONFINITE,
    WATCH,
    CoreLink,
)
from .newton import NewtonSystem, newton_system

__all__ = ["BDF", "BDFDenseOutput", "IntegrationError"]

# IDA's constants.
MAX_ORDER = 5     # the highest BDF order (the compiled loop's KV_MAXORD)
_EPS_NEWT = 0.33  # Newton tolerance, relative to the error-test norm (IDA's epcon)
_TOL_DEL = 1e-4 * _EPS_NEWT  # first-correction tolerance for immediate acceptance
_RATE_MAX = 0.9  # Newton convergence-rate bound
_XRATE = 0.25  # cj ratio band: re-factorise outside [(1-x)/(1+x), (1+x)/(1-x)]
_CJ_LO = (1.0 - _XRATE) / (1.0 + _XRATE)
_CJ_HI = 1.0 / _CJ_LO

_EPS16 = 16.0 * float(np.finfo(float).eps)
_OK = 0
_CONV_FAIL = 1
_ERR_FAIL = 2


class IntegrationError(RuntimeError):
    """The integrator could not continue.

    Attributes
    ----------
    t : float
        Time of the last accepted step.
    y, yp : ndarray
        State and its rate at the last accepted step (copies).
    h : float
        The step size last attempted.
    residual_norm : float
        Max-norm of the residual at the last attempted iterate (inf if non-finite).
    worst_index : int
        Index of the component that caused the failure: the first non-finite residual
        entry, else the largest weighted Newton correction or local error.
    """

    def __init__(
        self,
        message: str,
        *,
        t: float,
        y: np.ndarray,
        yp: np.ndarray,
        h: float,
        residual_norm: float,
        worst_index: int,
    ) -> None:
        super().__init__(message)
        self.t = t
        self.y = y
        self.yp = yp
        self.h = h
        self.residual_norm = residual_norm
        self.worst_index = worst_index


@functools.cache
def stability_extents() -> dict[int, float]:
    """D_k for BDF orders k = 1..5: how far the unstable region of BDF-k reaches into the
    left half-plane, ``max -Re z`` on its boundary locus ``z(theta) = sum_j (1 -
    exp(-i theta))^j / j`` (j = 1..k). A mode with ``Re(h lambda) <= -D_k`` is damped by
    BDF-k whatever its frequency. D_1 = D_2 = 0 (A-stable), D_3 = 1/12, D_4 = 2/3,
    D_5 = 2.327 (Hairer and Wanner, Solving ODEs II, Sect. V.2)."""
    def re_z(theta: np.ndarray, k: int) -> np.ndarray:
        w = 1.0 - np.exp(-1j * theta)
        acc = w / k
        for j in range(k - 1, 0, -1):       # Horner: w (1 + w (1/2 + w (1/3 + ...)))
            acc = w * (1.0 / j + acc)
        return acc.real

    out = {}
    for k in range(1, MAX_ORDER + 1):
        # a coarse grid, zoomed in on the minimum (x 200 a time): theta to ~1e-13, D_k to
        # round-off, in ~1 ms (a process of a Maxwell rod computes this once)
        grid = np.linspace(0.0, np.pi, 401)
        for _ in range(6):
            i = int(np.argmin(re_z(grid, k)))
            grid = np.linspace(grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)], 401)
        extent = -float(re_z(grid, k).min())
        out[k] = extent if extent > 1e-12 else 0.0      # BDF1-2: the locus touches 0
    return out


class BDF:
    """IDA-style variable-order (1..5) variable-step BDF solver for ``F(t, y, y') = 0``.

    Shaped like :class:`scipy.integrate.OdeSolver`: call :meth:`step` until ``status``
    is ``'finished'``; ``t``, ``y``, ``yp`` are the last accepted point (``y`` and ``yp``
    are internal buffers: copy them to keep them past the next step).

    Parameters
    ----------
    problem : ResidualProblem
        Residual, Jacobian and layout (``runtime.solvers.protocols.ResidualProblem``).
    t0, y0, yp0 : float, ndarray, ndarray
        Consistent initial values (see ``consistent_initial``).
    t_bound : float
        End of the integration; the last step lands on it exactly.
    rtol, atol : float or ndarray
        Tolerances; weights ``1/(rtol |y_i| + atol_i)``, ``atol`` scalar or (n,).
    max_order : int
        Highest BDF order, 1 ... 5.
    first_step : float, optional
        Initial step size (default: IDA's choice from ``|y'|``).
    max_step : float
        Largest step size magnitude.
    suppress_alg : bool
        Exclude algebraic components from the local error test.
    error_mask : ndarray of bool, optional
        The unknowns in the local error test (default: all; with ``suppress_alg`` the
        algebraic ones are left out too). The others are left to the corrector, as IDA's
        suppressalg leaves the algebraic unknowns: a structural model can control its
        configuration and leave the velocities out.
    stiff_decay_rate : float
        Slowest decay rate sigma (1/s) of the problem's stiff, lightly damped modes
        (default 0: none). Order k >= 3 is then chosen only on steps with
        ``|h| sigma >= D_k`` (``stability_extents``): BDF3-5 are not A-stable, and
        a mode ``h lambda`` with ``Re(h lambda) > -D_k`` near the imaginary axis may fall
        in their unstable lobe, where its growth, caught by the error test only, holds
        the step at the stability limit (CVODE's STALD detects this after the fact;
        here the spectrum is known).
    fixed_step : float, optional
        Take steps of exactly this size without error control (the order rises by one
        per step up to ``max_order``; ``max_step`` is ignored); for convergence studies.
    max_nonlinear_iter : int
        Newton iterations per attempt (IDA: 4).
    max_conv_fails, max_error_fails : int
        Consecutive failures on one step before giving up.
    min_step : float
        Smallest step size magnitude allowed (besides round-off at ``t``).
    condense : bool
        Solve the Newton systems condensed when the problem names kinematic blocks
        (``condensation_blocks()``) and the C helpers are available.
    sensitivities : tuple, optional
        Forward sensitivities ``(s0, sp0, pbar)``: consistent initial sensitivities and
        their rates (k, n) and the parameters' sizes (k,) (``runtime/solvers/
        sensitivity.py``: IDAS's staggered corrector, the same steps); the problem then
        provides ``sensitivity_residual`` (and, for the compiled loop,
        ``c_sensitivities``).
    sens_errcon : bool
        The sensitivities in the local error test and the order selection (IDAS's
        ``errconS``; default False: the steps are the state's alone).
    compiled_loop : bool
        Take the steps in C (``native/step_loop.c``: the same algorithm, statement for
        statement) when the C helpers are available; else, or with False, in Python.
        The problem's compiled kernels (``c_kernels()``) are then called from C, other
        problems through callbacks.

    Notes
    -----
    Counters: ``nstep``, ``nfev`` (residual calls), ``njev`` (Jacobian calls), ``nlu``
    (factorisations), ``nni`` (Newton iterations), ``netf`` (error-test failures),
    ``ncfn`` (Newton convergence failures).
    """

    def __init__(
        self,
        problem: ResidualProblem,
        t0: float,
        y0: np.ndarray,
        yp0: np.ndarray,
        t_bound: float,
        rtol: float = 1e-6,
        atol: float | np.ndarray = 1e-8,
        max_order: int = 5,
        first_step: float | None = None,
        max_step: float = np.inf,
        suppress_alg: bool = False,
        error_mask: np.ndarray | None = None,
        stiff_decay_rate: float = 0.0,
        *,
        fixed_step: float | None = None,
        max_nonlinear_iter: int = 4,
        max_conv_fails: int = 10,
        max_error_fails: int = 10,
        min_step: float = 0.0,
        condense: bool = True,
        sensitivities: tuple | None = None,
        sens_errcon: bool = False,
        compiled_loop: bool = True,
    ) -> None:
        n = int(problem.n)
        y0 = np.asarray(y0, dtype=float)
        yp0 = np.asarray(yp0, dtype=float)
        if y0.shape != (n,) or yp0.shape != (n,):
            raise ValueError(f"y0 and yp0 must have shape ({n},), got {y0.shape}, {yp0.shape}")
        if not 1 <= max_order <= 5:
            raise ParameterError("max_order", max_order, "integers 1..5")
        if not (rtol == 0.0 or rtol >= 100 * np.finfo(float).eps):
            raise ParameterError("rtol", rtol, f"0 or >= {100 * np.finfo(float).eps:.3g}")
        atol_arr = np.broadcast_to(np.asarray(atol, dtype=float), (n,)).copy()
        if not np.all(atol_arr > 0.0):
            raise ParameterError("atol", atol, f"> 0, scalar or shape ({n},)")
        if not max_step > 0.0:
            raise ParameterError("max_step", max_step, "> 0")
        if fixed_step is not None and not abs(fixed_step) > 0.0:
            raise ParameterError("fixed_step", fixed_step, "nonzero or None")
        if not (np.all(np.isfinite(y0)) and np.all(np.isfinite(yp0))):
            raise ValueError("y0 and yp0 must be finite")

        self.problem = problem
        self.n = n
        self.kl, self.ku = int(problem.kl), int(problem.ku)
        self.t_bound = float(t_bound)
        self.direction = 1.0 if self.t_bound >= t0 else -1.0
        self.rtol = float(rtol)
        self.atol = atol_arr
        self.max_order = int(max_order)
        if not (math.isfinite(stiff_decay_rate) and stiff_decay_rate >= 0.0):
            raise ParameterError("stiff_decay_rate", stiff_decay_rate, "finite, >= 0 (1/s)")
        #: smallest step size ``|h|`` at which order k may be chosen (index k; 0: no bound)
        self._stab_hmin = [0.0] * (MAX_ORDER + 2)
        if stiff_decay_rate > 0.0:
            for k, extent in stability_extents().items():
                if k >= 3:
                    self._stab_hmin[k] = extent / stiff_decay_rate
        self.max_step = float(max_step)
        self.suppress_alg = bool(suppress_alg)
        self.fixed_step = None if fixed_step is None else abs(float(fixed_step))
        self.max_nonlinear_iter = int(max_nonlinear_iter)
        self.max_conv_fails = int(max_conv_fails)
        self.max_error_fails = int(max_error_fails)
        self.min_step = float(min_step)
        self.status = "running" if self.t_bound != t0 else "finished"

        self.nstep = self.nfev = self.njev = self.nlu = 0
        self.nni = self.netf = self.ncfn = 0
        self._nst0 = 0  # nstep at the last (re)start (IDA's first-step logic counts from it)

        # Work arrays (all allocated once).
        mo = self.max_order
        self._phi = np.zeros((mo + 2, n))
        self._y = y0.copy()  # accepted y, yp at self.t
        self._yp = yp0.copy()
        self._yy = np.empty(n)  # Newton iterates
        self._ypw = np.empty(n)
        self._ee = np.zeros(n)
        self._res = np.empty(n)
        self._tmp = np.empty(n)
        self._ewt = np.empty(n)
        #: rows F_i = y_i - g_i(t) of prescribed unknowns (``problem.exact_rows``,
        #: optional): their Newton corrections are taken unscaled (native/step_loop.c, kv_ida)
        self._exact = np.ascontiguousarray(getattr(problem, "exact_rows", ()),
                                           dtype=np.int32).ravel()
        self._exact_res = np.zeros(max(self._exact.size, 1))
        diff = np.asarray(problem.differential, dtype=bool)
        mask = np.ones(n, dtype=bool) if error_mask is None else np.asarray(error_mask, bool)
        if mask.shape != (n,) or not mask.any():
            raise ParameterError("error_mask", error_mask, f"a bool array of shape ({n},) "
                                 "with at least one True")
        if self.suppress_alg:
            mask = mask & diff
        #: the state's change of the error test's weights (contact: looser velocity
        #: tolerances near obstacles; the problem's ``state_error_weights(y, rtol, atol,
        #: w)``, changing w in place), None without; applied whenever the weights are
        self._state_error_weights = getattr(problem, "state_error_weights", None)
        masked = (self.suppress_alg or error_mask is not None
                  or self._state_error_weights is not None)
        self._errmask = mask.astype(float) if masked else None
        self._ewt_err = np.empty(n) if masked else self._ewt
        self._ab = band_storage(n, self.kl, self.ku)
        self._have_lu = False
        # The compiled helpers (runtime/solvers/native: flush-to-zero band and condensed
        # solves, fused Newton update, norms, interpolation), or None: the NumPy path.
        self._c = _native.load() if n > 0 else None
        if self._c is not None:
            self._ptrs = {id(a): a.ctypes.data
                          for a in (self._ee, self._res, self._ewt, self._ewt_err)}
        # The Newton systems (runtime/solvers/newton.py): condensed when the problem names
        # its kinematic blocks (the rod: phi' = v, p' = 1/2 p*(0, Omega)), so the LU and
        # the solves work on about half the unknowns and a narrower band (3.8x fewer
        # bytes); else the band LU of the whole matrix.
        self._newton: NewtonSystem = newton_system(problem, self._ab, self.kl, self.ku,
                                                   self._c, condense)

        # IDA's scalar state; coefficient lists are Python floats (fast scalar loops).
        self._psi = [0.0] * (mo + 2)
        self._alpha = [0.0] * (mo + 2)
        self._beta = [0.0] * (mo + 2)
        self._sigma = [0.0] * (mo + 2)
        self._gamma = [0.0] * (mo + 2)
        self._kk = 1
        self._kused = 0
        self._knew = 1
        self._hused = 0.0
        self._ns = 0
        self._phase = 0
        self._cj = 0.0
        self._cjold = 0.0
        self._cjlast = 0.0
        self._cjratio = 1.0
        self._ss = 20.0
        self._oldnrm = 0.0
        self._rr = 1.0
        self._hmax_inv = 1.0 / self.max_step
        self._fail_index = -1  # component blamed in failure reports
        #: the state's bound on the next step (contact: no segment moves toward an
        #: obstacle by more than a fraction of its gap; the problem's state_max_step(t, y),
        #: None without), applied after every accepted step and to the first
        self._state_max_step = getattr(problem, "state_max_step", None)

        self.t = float(t0)
        self.t_old: float | None = None
        self._update_weights()

        # Reject a non-finite initial residual at once.
        problem.residual(self.t, self._y, self._yp, self._res)
        self.nfev += 1
        if not np.all(np.isfinite(self._res)):
            self._raise_nonfinite(self.t, self._y, self._yp, 0.0)

        #: forward sensitivities (runtime/solvers/sensitivity.py), or None
        self._sens = None
        self._lu_stamp = -1     # nstep at the state's last factorisation
        if sensitivities is not None:
            from .sensitivity import StaggeredSensitivities

            own = None            # the sensitivities' own Newton system (not an assembly's)
            if not hasattr(problem, "newton_system"):
                own = newton_system(problem, band_storage(n, self.kl, self.ku), self.kl,
                                    self.ku, self._c, condense)
            self._sens = StaggeredSensitivities(self, *sensitivities, errcon=sens_errcon,
                                                own=own)
        self._start_history(first_step)
        # The compiled step loop (runtime/solvers/native/step_loop.c), from this state on.
        self._core = (CoreLink(self._c, self)
                      if self._c is not None and compiled_loop and n > 0 else None)

    def _start_history(self, first_step: float | None) -> None:
        """IDA's start (IDAInitialSetup and the first step's h): order 1, history
        ``phi = [y, h y']`` from the current ``t, y, y'``; the first step ``first_step``
        or, by IDA's rule, ``0.001 (t_bound - t)`` limited by ``0.5 / |y'|_wrms``."""
        tdist = abs(self.t_bound - self.t)
        if self.fixed_step is not None:
            h = self.fixed_step
        elif first_step is not None:
            h = abs(float(first_step))
            if not h > 0.0:
                raise ParameterError("first_step", first_step, "nonzero or None")
        else:
            h = 0.001 * tdist if tdist > 0 else 1.0
            ypnorm = self._wrms(self._yp, self._ewt_err)
            if ypnorm > 0.5 / h:
                h = 0.5 / ypnorm
        if self.fixed_step is None:
            h = min(h, self.max_step)
        if tdist > 0:
            h = min(h, tdist)
        if self.fixed_step is None and self._state_max_step is not None:
            h = min(h, max(self._state_max_step(self.t, self._y), self._hmin()))
        self._hh = self.direction * h
        self._phi[0] = self._y
        np.multiply(self._yp, self._hh, out=self._phi[1])
        self._psi[0] = self._hh
        self._cj = 1.0 / self._hh
        if self._sens is not None:
            self._sens.start_history(self._hh)

    # ------------------------------------------------------------------ public API
    @property
    def y(self) -> np.ndarray:
        """State at ``t`` (shape (n,)); an internal buffer valid until the next step."""
        return self._y

    @property
    def yp(self) -> np.ndarray:
        """Derivative ``y'`` at ``t`` (shape (n,)); an internal buffer."""
        return self._yp

    @property
    def step_size(self) -> float | None:
        """Size of the last accepted step (None before the first)."""
        return None if self.t_old is None else abs(self.t - self.t_old)

    @property
    def order(self) -> int:
        """Order used on the last accepted step (0 before the first)."""
        return self._kused

    @property
    def counters(self) -> dict[str, int]:
        out = {
            "nstep": self.nstep,
            "nfev": self.nfev,
            "njev": self.njev,
            "nlu": self.nlu,
            "nni": self.nni,
            "netf": self.netf,
            "ncfn": self.ncfn,
        }
        if self._sens is not None:
            out.update(self._sens.counters)
        return out

    @property
    def n_sensitivities(self) -> int:
        """Number k of forward sensitivities (0: none)."""
        return 0 if self._sens is None else self._sens.k

    @property
    def sensitivities(self) -> np.ndarray | None:
        """The sensitivities at ``t``, (k, n) (an internal buffer), or None."""
        return None if self._sens is None else self._sens.y.reshape(self._sens.k, self.n)

    @property
    def sensitivity_rates(self) -> np.ndarray | None:
        """Their rates s' at ``t``, (k, n) (an internal buffer), or None."""
        return None if self._sens is None else self._sens.yp.reshape(self._sens.k, self.n)

    def step(self) -> str | None:
        """Take one accepted step; return None, or a message when finished.

        Raises :class:`IntegrationError` on failure (``status`` becomes ``'failed'``).
        """
        if self.status != "running":
            raise RuntimeError("Attempt to step on a failed or finished solver.")
        if self.n == 0 or self.t == self.t_bound:
            self.t_old = self.t
            self.t = self.t_bound
            self.status = "finished"
            return None
        if self._core is not None:
            self._advance_core(self.t_bound, 1)
        else:
            try:
                self._step_impl()
            except IntegrationError:
                self.status = "failed"
                raise
        if self.direction * (self.t - self.t_bound) >= 0.0:
            self.status = "finished"
        return None

    def advance(self, t_stop: float, max_steps: int = 2**62) -> str:
        """Take steps until ``t`` reaches ``t_stop`` (the step that reaches it is
        completed, so ``t`` may pass it: interpolate back with :meth:`dense_output`), a
        watched sign change (:meth:`watch`), ``max_steps`` steps or the end.

        Returns ``"tstop"``, ``"watch"``, ``"max_steps"`` or ``"finished"``. Without the
        compiled step loop, one step per call (``"max_steps"`` unless another applies).
        Raises :class:`IntegrationError` on failure, as :meth:`step`.
        """
        if self.status != "running":
            raise RuntimeError("Attempt to step on a failed or finished solver.")
        if self._core is None or self.n == 0 or self.t == self.t_bound:
            self.step()
            code = MAXSTEPS
        else:
            code = self._advance_core(t_stop, max(int(max_steps), 1))
        if self.direction * (self.t - self.t_bound) >= 0.0:
            self.status = "finished"
            return "finished"
        if code == WATCH:
            return "watch"
        if self.direction * (self.t - t_stop) >= 0.0:
            return "tstop"
        return "max_steps"

    @property
    def compiled(self) -> bool:
        """True when the steps run in the compiled loop (``native/step_loop.c``)."""
        return self._core is not None

    @property
    def core(self) -> CoreLink | None:
        """The compiled loop (energy audit and output samples can run inside it), or
        None."""
        return self._core

    def watch(self, watches: list[tuple[int, float]], kept=()) -> None:
        """Make :meth:`advance` stop after a step in which ``y[index]`` changes sign in
        ``direction`` (< 0: from > 0 to <= 0, > 0: from < 0 to >= 0); at most 8. The
        watches flagged in ``kept`` (booleans, one per watch) keep such a step for the
        replayed steps' sink instead, where those are enabled
        (``CoreLink.enable_replay``). No effect without the compiled loop (which stops
        after every step anyway)."""
        if self._core is not None:
            self._core.set_watches(watches, kept)

    def extend(self, t_bound: float) -> None:
        """Move the end of the integration to ``t_bound`` (in the same direction, not
        behind ``t``): the steps go on with their history and land on it exactly. With
        :meth:`restart`, what a run driver uses to stop at every breakpoint of its
        inputs (IDA's ``IDASetStopTime``)."""
        t_bound = float(t_bound)
        if not math.isfinite(t_bound) or self.direction * (t_bound - self.t) < 0.0:
            raise ParameterError("t_bound", t_bound, f"finite and not behind t = {self.t!r} "
                                 "in the direction of integration")
        self.t_bound = t_bound
        self.status = "running" if t_bound != self.t else "finished"
        if self._core is not None:
            self._core.s.t_bound = t_bound

    def set_max_step(self, max_step: float) -> None:
        """Largest step size magnitude from now on (s)."""
        if not max_step > 0.0:
            raise ParameterError("max_step", max_step, "> 0")
        self.max_step = float(max_step)
        self._hmax_inv = 1.0 / self.max_step
        if self._core is not None:
            self._core.s.hmax_inv = self._hmax_inv
        if abs(self._hh) > self.max_step:          # the next step obeys it at once
            self._hh = math.copysign(self.max_step, self._hh)
            if self._core is not None:
                self._core.s.hh = self._hh

    def restart(self, y: np.ndarray, yp: np.ndarray, first_step: float | None = None,
                s: np.ndarray | None = None, sp: np.ndarray | None = None) -> None:
        """Start afresh at the current ``t`` from consistent ``y, y'`` (order 1, a new
        history, a new Jacobian), as IDA does after ``IDAReInit``: at an input's
        breakpoint where a load, a prescribed motion or its rate jumps, the history
        before it does not describe the solution after it. The counters go on;
        ``first_step``: as in the constructor (default: IDA's rule). With sensitivities,
        ``s``, ``sp`` (k, n): their consistent values (default: s kept, s' zero)."""
        y = np.asarray(y, dtype=float)
        yp = np.asarray(yp, dtype=float)
        if y.shape != (self.n,) or yp.shape != (self.n,):
            raise ValueError(f"y and yp must have shape ({self.n},), got {y.shape}, "
                             f"{yp.shape}")
        if not (np.all(np.isfinite(y)) and np.all(np.isfinite(yp))):
            raise ValueError("y and yp must be finite")
        if self.status == "failed":
            raise RuntimeError("Attempt to restart a failed solver.")
        self._y[:] = y
        self._yp[:] = yp
        self._kk, self._kused, self._knew = 1, 0, 1
        self._hused, self._ns, self._phase = 0.0, 0, 0
        self._cjold = self._cjlast = 0.0
        self._cjratio, self._ss, self._oldnrm, self._rr = 1.0, 20.0, 0.0, 1.0
        self._have_lu = False
        self._nst0 = self.nstep
        self._update_weights()
        if self._sens is not None:
            sens = self._sens
            sens.y[:] = sens.y if s is None else np.asarray(s, dtype=float).reshape(-1)
            sens.yp[:] = 0.0 if sp is None else np.asarray(sp, dtype=float).reshape(-1)
            sens.update_weights(self.rtol)
        self._start_history(first_step)
        if self._core is not None:
            self._core.push(self)

    def _advance_core(self, t_stop: float, max_steps: int) -> int:
        core = self._core
        try:
            code = core.advance(t_stop, max_steps)    # the state is pulled back either way
        except BaseException:
            self.status = "failed"
            raise
        if code >= 0:
            return code
        self.status = "failed"
        s = core.s
        if code == NONFINITE:
            self._raise_nonfinite(s.fail_t, self._yy, self._ypw, self._hh)
        if code == FAIL_STALL:
            self._raise_failure(self._stall_reason(), at_accepted=True)
        if code == CALLBACK:
            self._raise_failure("a compiled function of the problem (residual, Jacobian or "
                                "energies) returned an error code")
        reasons = {
            FAIL_CONV: f"the Newton iteration failed to converge {s.fail_count} "
                              "times in a row",
            FAIL_ERR: f"the local error test failed {s.fail_count} times in a row",
            FAIL_FIXED: "the Newton iteration failed at the fixed step size",
            FAIL_HMIN: self._hmin_reason(_CONV_FAIL if s.fail_nflag == _CONV_FAIL
                                                else _ERR_FAIL),
        }
        self._raise_failure(reasons[code])
        raise AssertionError("unreachable")

    def dense_output(self, copy: bool = True) -> BDFDenseOutput:
        """Interpolant of the last accepted step (y and y'), valid on ``[t_old, t]``.

        ``copy=False`` shares the solver's history arrays: valid only until the next
        :meth:`step` (the run loop's observers use it at once; at N = 1000 the copy was
        0.6 MB per step)."""
        if self.t_old is None:
            raise RuntimeError("dense_output() is available after the first step")
        k = max(self._kused, 1)
        phi = self._phi[: k + 1]
        dense = BDFDenseOutput(self.t_old, self.t, phi.copy() if copy else phi,
                               np.array(self._psi[: k + 1]), self._c)
        if self._sens is not None:
            sphi = self._sens.phi[: k + 1]
            dense.sens = BDFDenseOutput(self.t_old, self.t, sphi.copy() if copy else sphi,
                                        np.array(self._psi[: k + 1]), self._c)
        return dense

    # ------------------------------------------------------------------ internals
    def _wrms(self, v: np.ndarray, w: np.ndarray) -> float:
        if self._c is not None:  # flush-to-zero norm (see runtime/solvers/native)
            ptrs = self._ptrs
            pv, pw = ptrs.get(id(v)), ptrs.get(id(w))
            return self._c.kv_wrms(self.n, pv if pv is not None else v.ctypes.data, None,
                                   pw if pw is not None else w.ctypes.data)
        tmp = self._tmp
        np.multiply(v, w, out=tmp)
        return math.sqrt(float(np.dot(tmp, tmp)) / self.n)

    def _update_weights(self) -> None:
        ewt = self._ewt
        np.abs(self._y, out=ewt)
        ewt *= self.rtol
        ewt += self.atol
        np.reciprocal(ewt, out=ewt)
        if self._errmask is not None:
            np.multiply(ewt, self._errmask, out=self._ewt_err)
        if self._state_error_weights is not None:
            self._state_error_weights(self._y, self.rtol, self.atol, self._ewt_err)

    def _hmin(self) -> float:
        return max(self.min_step, _EPS16 * abs(self.t), 1e-300)

    def _set_coeffs(self) -> float:
        """IDASetCoeffs: BDF coefficients for the current h and order; phi -> phi*."""
        kk, hh = self._kk, self._hh
        psi, alpha, beta, sigma, gamma = (
            self._psi,
            self._alpha,
            self._beta,
            self._sigma,
            self._gamma,
        )
        if hh != self._hused or kk != self._kused:
            self._ns = 0
        self._ns = min(self._ns + 1, self._kused + 2)
        ns = self._ns
        if kk + 1 >= ns:
            beta[0] = alpha[0] = sigma[0] = 1.0
            gamma[0] = 0.0
            temp1 = hh
            for i in range(1, kk + 1):
                temp2 = psi[i - 1]
                psi[i - 1] = temp1
                beta[i] = beta[i - 1] * psi[i - 1] / temp2
                temp1 = temp2 + hh
                alpha[i] = hh / temp1
                sigma[i] = i * sigma[i - 1] * alpha[i]
                gamma[i] = gamma[i - 1] + alpha[i - 1] / hh
            psi[kk] = temp1
        alphas = 0.0
        alpha0 = 0.0
        for i in range(kk):
            alphas -= 1.0 / (i + 1)
            alpha0 -= alpha[i]
        self._cjlast = self._cj
        self._cj = -alphas / hh
        ck = abs(alpha[kk] + alphas - alpha0)
        ck = max(ck, alpha[kk])
        phi = self._phi
        for i in range(ns, kk + 1):
            phi[i] *= beta[i]
        return ck

    def _predict(self) -> None:
        kk = self._kk
        phi, yy, ypw, tmp = self._phi, self._yy, self._ypw, self._tmp
        # Straight into the Newton iterates (the corrector starts from the prediction).
        # Summed term by term in order (not np.dot, whose BLAS kernels sum in another
        # order and fuse multiply-adds) so that this path rounds like native/step_loop.c.
        np.copyto(yy, phi[0])
        ypw.fill(0.0)
        gamma = self._gamma
        for j in range(1, kk + 1):
            yy += phi[j]
            np.multiply(phi[j], gamma[j], out=tmp)
            ypw += tmp

    def _restore(self) -> None:
        """IDARestore: undo the phi* scaling and the psi update of a failed attempt."""
        kk, hh = self._kk, self._hh
        psi = self._psi
        for j in range(1, kk + 1):
            psi[j - 1] = psi[j] - hh
        phi, beta = self._phi, self._beta
        for j in range(self._ns, kk + 1):
            phi[j] *= 1.0 / beta[j]
        if self._sens is not None:
            self._sens.restore(self)

    def _setup(self, t: float) -> bool:
        """Evaluate and factorise J at the current iterate; False if J is singular."""
        own = getattr(self._newton, "setup", None)
        if own is not None:                 # coupled blocks: the problem's own Jacobian
            info = own(t, self._yy, self._ypw, self._cj)
            self.njev += 1
        else:
            ab = self._ab
            ab.fill(0.0)
            self.problem.jacobian_band(t, self._yy, self._ypw, self._cj, ab)
            self.njev += 1
            info = self._newton.factor(self._cj)
        self.nlu += 1
        self._lu_stamp = self.nstep
        self._cjold = self._cj
        self._cjratio = 1.0
        self._ss = 20.0
        if self._sens is not None:
            self._sens.ss = 20.0
        self._have_lu = info == 0
        return info == 0

    def _nls(self, tnew: float) -> int:
        """Corrector: simplified Newton for the correction ``ee``; _OK or _CONV_FAIL."""
        call_setup = False
        sens = self._sens
        if self.nstep == self._nst0 and not self._have_lu:
            self._cjold = self._cj
            self._ss = 20.0
            if sens is not None:
                sens.ss = 20.0
            call_setup = True
        self._cjratio = self._cj / self._cjold
        if self._cjratio < _CJ_LO or self._cjratio > _CJ_HI or not self._have_lu:
            call_setup = True
        if self._cj != self._cjlast:
            self._ss = 100.0
            if sens is not None:
                sens.ss = 100.0

        problem = self.problem
        yy, ypw, ee, res = self._yy, self._ypw, self._ee, self._res
        ewt, tmp = self._ewt, self._tmp
        maxcor = self.max_nonlinear_iter
        correct = self._newton.correct

        first = True
        while True:
            if not first:
                self._predict()  # retry from the prediction with a fresh Jacobian
            first = False
            ee.fill(0.0)
            problem.residual(tnew, yy, ypw, res)
            self.nfev += 1
            jcur = False
            if call_setup:
                jcur = True
                if not self._setup(tnew):
                    self._fail_index = int(np.argmax(np.abs(res, out=self._tmp)))
                    return _CONV_FAIL
            cj = self._cj
            scale = 2.0 / (1.0 + self._cjratio) if self._cjratio != 1.0 else 1.0
            m = 0
            exact, exact_res = self._exact, self._exact_res
            while True:
                if exact.size:
                    exact_res[:exact.size] = res[exact]
                delnrm = correct(res, scale, ewt, ee, yy, ypw, cj)
                if not math.isfinite(delnrm):
                    self._raise_nonfinite(tnew, yy, ypw, self._hh)
                if exact.size:
                    self._exact_rows_finish(scale)
                self.nni += 1
                if m == 0:
                    self._oldnrm = delnrm
                    if delnrm <= _TOL_DEL:
                        return _OK
                else:
                    rate = (delnrm / self._oldnrm) ** (1.0 / m)
                    if rate > _RATE_MAX:
                        break
                    self._ss = rate / (1.0 - rate)
                if self._ss * delnrm <= _EPS_NEWT:
                    return _OK
                m += 1
                if m >= maxcor:
                    break
                problem.residual(tnew, yy, ypw, res)
                self.nfev += 1
            # Recoverable failure: retry once with a fresh Jacobian, else report the
            # component with the largest weighted correction.
            np.multiply(res, ewt, out=tmp)
            self._fail_index = int(np.argmax(np.abs(tmp, out=tmp)))
            if jcur:
                return _CONV_FAIL
            call_setup = True

    def _exact_rows_finish(self, scale: float) -> None:
        """After a Newton update: the part (1 - scale) F_i of the exact rows' corrections
        that the scale left out (as ``exact_rows_finish`` in native/step_loop.c)."""
        if scale == 1.0:
            return
        for k, i in enumerate(self._exact):
            d = (1.0 - scale) * self._exact_res[k]
            self._ee[i] -= d
            self._yy[i] -= d
            self._ypw[i] -= self._cj * d

    def _test_error(self, ck: float) -> tuple[int, float, float, float]:
        """IDATestError: local error estimates at orders k, k-1, k-2 and the test."""
        kk = self._kk
        sigma = self._sigma
        ee, phi, w = self._ee, self._phi, self._ewt_err
        enorm_k = self._wrms(ee, w)
        err_k = sigma[kk] * enorm_k
        terr_k = (kk + 1) * err_k
        err_km1 = err_km2 = 0.0
        self._knew = kk
        if kk > 1:
            delta = self._res  # free here: it held the last Newton correction
            np.add(phi[kk], ee, out=delta)
            err_km1 = sigma[kk - 1] * self._wrms(delta, w)
            terr_km1 = kk * err_km1
            if kk > 2:
                delta += phi[kk - 1]
                err_km2 = sigma[kk - 2] * self._wrms(delta, w)
                terr_km2 = (kk - 1) * err_km2
                if max(terr_km1, terr_km2) <= terr_k:
                    self._knew = kk - 1
            elif terr_km1 <= 0.5 * terr_k:
                self._knew = kk - 1
        if ck * enorm_k > 1.0:
            np.multiply(ee, w, out=self._tmp)
            self._fail_index = int(np.argmax(np.abs(self._tmp, out=self._tmp)))
            return _ERR_FAIL, err_k, err_km1, err_km2
        return _OK, err_k, err_km1, err_km2

    def _step_impl(self) -> None:
        ncf = nef = 0
        tn = self.t
        while True:
            # Land exactly on t_bound (stretching h by round-off rather than leaving a
            # sliver of a step behind).
            remaining = self.t_bound - tn
            if self.direction * (self._hh - remaining) > -1e-8 * abs(self._hh):
                if self.nstep == self._nst0:
                    self._phi[1] *= remaining / self._hh
                    if self._sens is not None:
                        self._sens.rescale_first(remaining / self._hh)
                    self._psi[0] = remaining
                self._hh = remaining
            hh = self._hh
            if abs(hh) < self._hmin():
                # The error estimate drove h below round-off at t (t + h == t): stalled.
                self._raise_failure(self._stall_reason(), at_accepted=True)
            ck = self._set_coeffs()
            tnew = tn + hh
            if hh == remaining:
                tnew = self.t_bound
            self._predict()
            nflag = self._nls(tnew)
            err_k = err_km1 = 0.0
            if nflag == _OK and self.fixed_step is None:
                nflag, err_k, err_km1, err_km2 = self._test_error(ck)
            if nflag == _OK and self._sens is not None:     # IDAS's staggered corrector
                nflag = self._sens.nls(self, tnew)
                if nflag == _OK and self._sens.errcon and self.fixed_step is None:
                    errs = [err_k, err_km1, err_km2]
                    nflag = self._sens.test_error(self, ck, errs)
                    err_k, err_km1 = errs[0], errs[1]
            if nflag == _OK:
                break
            self._restore()
            if nflag == _CONV_FAIL:
                ncf += 1
            else:
                nef += 1
            self._handle_failure(nflag, ncf, nef, err_k, err_km1)
            if self.nstep == self._nst0:
                # IDAReset: rescale h*y'0 to the new step.
                self._psi[0] = self._hh
                self._phi[1] *= self._rr
                if self._sens is not None:
                    self._sens.rescale_first(self._rr)
        self._complete_step(tnew, err_k, err_km1)

    def _handle_failure(self, nflag: int, ncf: int, nef: int, err_k: float, err_km1: float) -> None:
        """IDAHandleNFlag: shrink h (and maybe the order) or raise IntegrationError."""
        self._phase = 1
        if nflag == _CONV_FAIL:
            self.ncfn += 1
            if self.fixed_step is not None:
                self._raise_failure("the Newton iteration failed at the fixed step size")
            if ncf >= self.max_conv_fails:
                self._raise_failure(f"the Newton iteration failed to converge {ncf} times in a row")
            self._rr = 0.25
        else:
            self.netf += 1
            if nef == 1:
                err_knew = err_k if self._kk == self._knew else err_km1
                self._kk = self._knew
                rr = 0.9 * (2.0 * err_knew + 1e-4) ** (-1.0 / (self._kk + 1))
                self._rr = max(0.25, min(0.9, rr))
            elif nef == 2:
                self._kk = self._knew
                self._rr = 0.25
            else:
                self._kk = 1
                self._rr = 0.25
            if nef >= self.max_error_fails:
                self._raise_failure(f"the local error test failed {nef} times in a row")
        self._hh *= self._rr
        if abs(self._hh) < self._hmin():
            self._raise_failure(self._hmin_reason(nflag))

    def _stall_reason(self) -> str:
        return (f"the step size {abs(self._hh):.3g} chosen by error control is below the "
                f"minimum {self._hmin():.3g} (t + h no longer advances t)")

    def _hmin_reason(self, nflag: int) -> str:
        what = "Newton convergence" if nflag == _CONV_FAIL else "the local error test"
        return f"the step size fell below the minimum {self._hmin():.3g} after failures of {what}"

    def _complete_step(self, tnew: float, err_k: float, err_km1: float) -> None:
        """IDACompleteStep: accept, choose the next order and step, update phi."""
        self.nstep += 1
        kk = self._kk
        kdiff = kk - self._kused
        self._kused = kk
        self._hused = self._hh
        mo = self.max_order     # lowered where the step is below an order's stability bound
        if self.fixed_step is None:
            while mo > 2 and abs(self._hh) < self._stab_hmin[mo]:
                mo -= 1
        phi, ee = self._phi, self._ee

        if self.fixed_step is not None:
            if self.nstep - self._nst0 > 1 and kk < mo:
                self._kk = kk + 1
            self._hh = self.direction * self.fixed_step
        else:
            if self._knew == kk - 1 or kk >= mo:
                self._phase = 1
            if self._phase == 0:
                if self.nstep - self._nst0 > 1:
                    self._kk = kk + 1
                    hnew = 2.0 * self._hh
                    tmp = abs(hnew) * self._hmax_inv
                    if tmp > 1.0:
                        hnew /= tmp
                    self._hh = hnew
            else:
                action = 0  # -1 lower, 0 maintain, +1 raise
                err_kp1 = 0.0
                if self._knew == kk - 1 or kk > mo:
                    action = -1
                elif kk == mo or kk + 1 >= self._ns or kdiff == 1:
                    action = 0
                else:
                    delta = self._res
                    np.subtract(ee, phi[kk + 1], out=delta)
                    enorm = self._wrms(delta, self._ewt_err)
                    if self._sens is not None and self._sens.errcon:
                        enorm = self._sens.order_norm(self, enorm)
                    err_kp1 = enorm / (kk + 2)
                    terr_k = (kk + 1) * err_k
                    terr_kp1 = (kk + 2) * err_kp1
                    if kk == 1:
                        action = 0 if terr_kp1 >= 0.5 * terr_k else 1
                    else:
                        terr_km1 = kk * err_km1
                        if terr_km1 <= min(terr_k, terr_kp1):
                            action = -1
                        elif terr_kp1 >= terr_k:
                            action = 0
                        else:
                            action = 1
                if action == 1:
                    self._kk = kk + 1
                    err_knew = err_kp1
                elif action == -1:
                    self._kk = kk - 1
                    err_knew = err_km1
                else:
                    err_knew = err_k
                hnew = self._hh
                rr = (2.0 * err_knew + 1e-4) ** (-1.0 / (self._kk + 1))
                if rr >= 2.0:
                    hnew = 2.0 * self._hh
                    tmp = abs(hnew) * self._hmax_inv
                    if tmp > 1.0:
                        hnew /= tmp
                elif rr <= 1.0:
                    rr = max(0.5, min(0.9, rr))
                    hnew = self._hh * rr
                self._hh = hnew

        kused = self._kused
        if kused < self.max_order:
            np.copyto(phi[kused + 1], ee)
        phi[kused] += ee
        for j in range(kused - 1, -1, -1):
            phi[j] += phi[j + 1]
        if self._sens is not None:
            self._sens.complete(self, kused, self.rtol)

        self.t_old = self.t
        self.t = tnew
        # Accept the Newton iterate by swapping buffers (no copies).
        self._y, self._yy = self._yy, self._y
        self._yp, self._ypw = self._ypw, self._yp
        self._update_weights()
        if self._state_max_step is not None and self.fixed_step is None:
            hb = max(self._state_max_step(self.t, self._y), self._hmin())
            if abs(self._hh) > hb:
                self._hh = self.direction * hb

    # ------------------------------------------------------------------ failures
    def _residual_report(self, t: float, y: np.ndarray, yp: np.ndarray) -> tuple[float, int]:
        r = np.empty(self.n)
        self.problem.residual(t, y, yp, r)
        self.nfev += 1
        bad = ~np.isfinite(r)
        if bad.any():
            return math.inf, int(np.argmax(bad))
        return float(np.max(np.abs(r), initial=0.0)), -1

    def _raise_nonfinite(self, t: float, y: np.ndarray, yp: np.ndarray, h: float) -> None:
        rnorm, idx = self._residual_report(t, y, yp)
        if idx < 0:
            detail = (
                "the Newton correction is not finite although the residual is "
                "(singular or overflowing iteration matrix)"
            )
            idx = int(np.argmax(~np.isfinite(self._res)))
        else:
            detail = f"the residual is not finite (first bad component {idx})"
        self.status = "failed"
        where = (
            "at the initial values"
            if h == 0.0
            else f"while trying a step of h = {h:.3g} to t = {t:.9g}"
        )
        raise IntegrationError(
            f"Integration stopped at t = {self.t:.9g} (last accepted point) {where}: "
            f"{detail}. Nothing was integrated over the non-finite values; check the "
            "model and its inputs near this state.",
            t=self.t,
            y=self._y.copy(),
            yp=self._yp.copy(),
            h=h,
            residual_norm=rnorm,
            worst_index=idx,
        )

    def _raise_failure(self, reason: str, *, at_accepted: bool = False) -> None:
        h = self._hh
        if at_accepted:
            # No attempt was made: report the accepted point and its largest local error.
            rnorm, bad = self._residual_report(self.t, self._y, self._yp)
            np.multiply(self._ee, self._ewt, out=self._tmp)
            self._fail_index = int(np.argmax(np.abs(self._tmp, out=self._tmp)))
        else:
            rnorm, bad = self._residual_report(self.t + h, self._yy, self._ypw)
        where = "accepted point" if at_accepted else "iterate"
        idx = bad if bad >= 0 else self._fail_index
        self.status = "failed"
        raise IntegrationError(
            f"Integration failed after the accepted point t = {self.t:.9g}: {reason} "
            f"(last attempted step h = {h:.3g}, order {self._kk}). The residual max-norm "
            f"at the last {where} is {rnorm:.3g} and the worst component is index {idx}. "
            "This usually means a singularity or blow-up of the solution, an inconsistent "
            "or wrong Jacobian, or tolerances too strict for the problem's scaling.",
            t=self.t,
            y=self._y.copy(),
            yp=self._yp.copy(),
            h=h,
            residual_norm=rnorm,
            worst_index=idx,
        )
