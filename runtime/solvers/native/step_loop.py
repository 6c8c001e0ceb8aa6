"""The compiled step loop (``step_loop.c``) and its link to :class:`runtime.solvers.bdf.BDF`.

``step_loop.c`` runs IDA's step (the algorithm of ``bdf.py``, statement for statement) on a
struct that holds the solver's scalar state and the addresses of its NumPy arrays
(:class:`CoreStruct` below). :class:`CoreLink` builds that struct from a
solver, gives the C code the problem's functions and runs ``kv_ida_advance``:

* a problem with compiled kernels (``problem.c_kernels()``, a
  :class:`~runtime.solvers.protocols.CKernels`: the rod's C assembly) is called
  directly from C, its time-dependent loads through one Python callback that runs only when
  t leaves the interval on which they are constant;
* any other problem (``residual``/``jacobian_band`` in Python) through ctypes callbacks.

An exception raised inside a callback is kept and raised again once the C call returns:
C code cannot unwind Python frames. Signals (Ctrl-C, SIGTERM) are held while C runs
with callbacks and delivered once it has returned: Python raises a signal's exception at
whatever bytecode runs next, which may be the first line of a callback, before any
``try`` can catch it; ctypes would print it and drop it.
"""

from __future__ import annotations

import ctypes
import math
import os
import signal
import threading
from typing import Any

import numpy as np

from ..protocols import CKernels

#: a runtime.solvers.bdf.BDF (not imported here: bdf.py imports this module)
BDF = Any

#: the signals held while the compiled loop may call back into Python
_HELD = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM") if hasattr(signal, name))


def _call_holding_signals(s, fn, *args):
    """``(fn(*args), signals received meanwhile)``, the signals' handlers not run yet; a
    signal sets ``s.stop`` so that the compiled loop returns after its current step (only
    the main thread can set handlers; elsewhere signals are not delivered to Python
    code anyway)."""
    if threading.current_thread() is not threading.main_thread():
        return fn(*args), []
    pending: list[int] = []

    def hold(signum, frame):
        pending.append(signum)
        s.stop = 1

    saved = []
    try:
        for sig in _HELD:
            old = signal.getsignal(sig)
            if old is not None:                  # None: a handler not set from Python
                signal.signal(sig, hold)
                saved.append((sig, old))
        return fn(*args), pending
    finally:
        for sig, old in saved:
            signal.signal(sig, old)


def audit_thread_wanted() -> bool:
    """Whether the energy audit and the output samples may run on a second thread
    (``kv_ida.audit_async``): this process may use at least two CPUs, and
    ``KVROD_AUDIT_THREAD`` is not ``0`` (same results either way, bit for bit; the
    thread only moves ~a quarter of a run's loop off its critical path)."""
    if os.environ.get("KVROD_AUDIT_THREAD", "").strip() == "0":
        return False
    try:
        cpus = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cpus = os.cpu_count() or 1
    return cpus >= 2


#: return codes of kv_ida_advance
TSTOP, WATCH, FINISHED, MAXSTEPS = 0, 1, 2, 3
FAIL_CONV, FAIL_ERR, FAIL_STALL, FAIL_HMIN, FAIL_FIXED, CALLBACK, NONFINITE = range(-1, -8, -1)
MAXWATCH = 8
NH = 7          # history rows: max order 5 + 2
AUDIT_NODES = 4  # the energy audit's nodes (KV_AUDIT_NODES): a cubic through the last 4

RES_FN = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p,
                          ctypes.c_void_p, ctypes.c_void_p)
JAC_FN = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p,
                          ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int,
                          ctypes.c_void_p)
DRIVE_FN = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_double)
SRES_FN = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_void_p,
                           ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p,
                           ctypes.c_void_p)


def _fields(kind, *names):
    return [(name, kind) for name in names]


class CoreStruct(ctypes.Structure):
    """Mirror of ``kv_ida`` in step_loop.c (field for field; the size is checked at load)."""

    _I, _P, _D, _L = ctypes.c_int, ctypes.c_void_p, ctypes.c_double, ctypes.c_longlong
    _fields_ = (
        _fields(_I, "n", "kl", "ku", "ldab")
        + _fields(_P, "res", "jac", "en")
        + _fields(_I, "nen")
        + _fields(_P, "ctx", "drive")
        + _fields(_D, "drive_lo", "drive_hi", "drive_t")
        + _fields(_P, "cond", "phi", "y", "yp", "yy", "ypw", "ee", "res_v", "tmp", "ewt",
                  "ewt_err", "errmask", "atol", "ab", "ipiv", "prof")
        + _fields(_D, "rtol", "t_bound", "direction", "hmax_inv", "min_step", "fixed_step")
        + _fields(_I, "max_order", "maxcor", "max_conv_fails", "max_error_fails")
        + _fields(_D * NH, "stab_hmin")
        + _fields(_D * NH, "psi", "alpha", "beta", "sigma", "gamma")
        + _fields(_I, "kk", "kused", "knew", "ns", "phase", "have_lu")
        + _fields(_D, "hh", "hused", "cj", "cjold", "cjlast", "cjratio", "ss", "oldnrm",
                  "rr", "t", "t_old")
        + _fields(_I, "started")
        + _fields(_L, "nstep", "nfev", "njev", "nlu", "nni", "netf", "ncfn", "nst0")
        + _fields(_I, "fail_index", "fail_count", "fail_nflag")
        + _fields(_D, "fail_t")
        + _fields(_I, "nwatch")
        + _fields(_I * MAXWATCH, "watch_idx")
        + _fields(_D * MAXWATCH, "watch_dir", "watch_old")
        + _fields(_I, "watch_hit", "audit", "nh")
        + _fields(_D * AUDIT_NODES, "ht")
        + _fields(_D * (2 * AUDIT_NODES), "hg")
        + _fields(_D, "dissipated", "external_work")
        + _fields(_D * (2 * AUDIT_NODES), "coef")
        + _fields(_P, "wy", "wyp")
        + _fields(_I, "nsamp", "m_out", "k_out", "rec_w", "rec_cap", "rec_n")
        + _fields(_P, "samp_idx", "t_out", "rec", "flush", "sy", "syp")
        + _fields(_I, "timing")
        + _fields(_D * 6, "sec")
        + _fields(_I, "stop")
        + _fields(_P, "jac_cells", "jwin")
        + _fields(_I, "jwin_cols", "jchunk")
        + _fields(_I, "nexact")
        + _fields(_P, "exact", "exact_res")
        + _fields(_P, "blocks", "sysjac")
        + _fields(_I, "m_rep", "k_rep", "rep_w", "rep_cap", "rep_n")
        + _fields(_P, "t_rep", "rep", "rep_flush")
        + _fields(_P, "maxstep")
        + _fields(_I, "nsens", "errconS", "sscaled")
        + _fields(_P, "sres", "sctx", "sphi", "s_y", "s_yp", "s_yy", "s_ypw", "s_ee", "s_ewt",
                  "s_ewt_err", "s_mask", "s_atol", "s_res", "s_delta")
        + _fields(_D, "ssS")
        + _fields(_L, "nfevS", "nniS", "ncfnS", "netfS", "nsetupS")
        + _fields(_P, "srec", "s_wy", "s_wyp", "s_ab", "s_cond", "s_ipiv", "s_prof")
        + _fields(_D, "s_cj")
        + _fields(_L, "s_stamp", "lu_stamp")
        + _fields(_I, "s_have_lu")
        + _fields(_P, "errw")
        + _fields(_I, "m_grid", "k_grid")
        + _fields(_P, "t_grid", "grid_y", "grid_yp")
        + _fields(_P, "en_audit")
        + _fields(_P, "grid_idx", "grid_wy")
        + _fields(_I, "grid_nidx", "grid_slack")
        + _fields(_I, "audit_async", "async_cap", "async_runs")
        + _fields(_P, "async_buf")
        + _fields(_I, "en_no_yp", "watch_rep")
        + [("rep_nstep", ctypes.c_longlong)]
    )
    #: names of the entries of ``sec`` (seconds per part when ``timing`` is set)
    SECTIONS = ("residual", "jacobian", "lu", "newton_solve_update", "energies", "drive")


class CoreLink:
    """The compiled step loop of one :class:`~runtime.solvers.bdf.BDF` (see the module
    docstring). Built by the solver when the C helpers are available."""

    def __init__(self, lib: ctypes.CDLL, solver: BDF) -> None:
        self._lib = lib
        self._solver = solver
        s = CoreStruct()
        self.s = s
        self.ptr = ctypes.addressof(s)
        self._error: BaseException | None = None
        self._keep: list[Any] = []
        self._callbacks = False      # a function other than the drive is a Python callback
        self._drive_now = None       # constant loads: drive(t) before each run
        self._go = None              # loads moved with t: the drive callback's body
        n = solver.n
        # every buffer the C code may hand to a callback, by address
        self._arrays: dict[int, np.ndarray] = {}
        self._abs: dict[int, np.ndarray] = {solver._ab.ctypes.data: solver._ab}
        for a in (solver._y, solver._yp, solver._yy, solver._ypw, solver._res, solver._tmp,
                  solver._ee):
            self._arrays[a.ctypes.data] = a
        s.n, s.kl, s.ku, s.ldab = n, solver.kl, solver.ku, solver._ab.shape[0]
        problem = solver.problem
        get = getattr(problem, "c_kernels", None)
        kern: CKernels | None = get() if get is not None else None
        if kern is not None:
            s.res, s.jac, s.en, s.ctx = kern.residual, kern.jacobian, kern.energies, kern.ctx
            s.nen = kern.n_energies
            s.en_audit = getattr(kern, "audit_energies", 0) or None
            self._en_reentrant = bool(getattr(kern, "energies_reentrant", False))
            s.en_no_yp = int(not getattr(kern, "energies_read_rates", True))
            s.maxstep = kern.max_step or None
            s.errw = kern.error_weights or None
            self._keep.append(kern.keep)
            self.has_energies = bool(kern.energies)
            if kern.drive is not None and not kern.drive_constant:
                self._set_drive(kern.drive)
            else:
                # constant loads: driven from Python before each run (advance), so that
                # C never calls back for them (no callback: no signals to hold either)
                self._drive_now = kern.drive
                s.drive_lo, s.drive_hi = -math.inf, math.inf
        else:
            self._python_functions(problem)
            self.has_energies = False
            self._en_reentrant = False
            s.nen = 5
        s.drive_t = math.nan
        newton = solver._newton
        cond = getattr(newton, "cond", None)           # the condensed systems, if any
        s.cond = newton.cond_ptr
        blocks = getattr(newton, "blocks_ptr", None)   # coupled band blocks (assemblies)
        if blocks is not None:
            sysjac = getattr(kern, "system_jacobian", 0) if kern is not None else 0
            if not sysjac:
                raise RuntimeError("coupled band blocks need the problem's compiled system "
                                   "Jacobian (CKernels.system_jacobian)")
            s.blocks, s.sysjac = blocks, sysjac
        if kern is not None and kern.jacobian_cells and cond is not None \
                and cond.block_tridiagonal:
            jac_cells = kern.jacobian_cells
            need = cond.relaxation_need()
            relaxed = getattr(kern, "jacobian_cells_relaxed", None)
            if need is not None and relaxed is not None:
                # the relaxation blocks' rows and columns only as far as the
                # factorisation reads them (the Jacobian is never read beyond it here)
                jac_cells, set_need = relaxed
                set_need(need)
            self._jacobian_by_cells(jac_cells, cond.cell_starts)
        p = lambda a: a.ctypes.data if a is not None else None  # noqa: E731
        s.phi = p(solver._phi)
        s.y, s.yp, s.yy, s.ypw = p(solver._y), p(solver._yp), p(solver._yy), p(solver._ypw)
        s.ee, s.res_v, s.tmp, s.ewt = p(solver._ee), p(solver._res), p(solver._tmp), p(solver._ewt)
        s.ewt_err = p(solver._ewt_err)
        s.nexact, s.exact = solver._exact.size, p(solver._exact)
        s.exact_res = p(solver._exact_res)
        s.errmask = p(solver._errmask)
        s.atol = p(solver.atol)
        s.ab, s.ipiv, s.prof = p(solver._ab), p(newton.ipiv), p(newton.prof)
        s.rtol, s.t_bound, s.direction = solver.rtol, solver.t_bound, solver.direction
        s.hmax_inv, s.min_step = solver._hmax_inv, solver.min_step
        s.fixed_step = solver.fixed_step or 0.0
        s.max_order, s.maxcor = solver.max_order, solver.max_nonlinear_iter
        s.stab_hmin[:] = solver._stab_hmin
        s.max_conv_fails, s.max_error_fails = solver.max_conv_fails, solver.max_error_fails
        self._sens_arrays: dict[int, np.ndarray] = {}
        if solver._sens is not None:
            self._link_sensitivities(solver, kern is not None)
        self.push(solver)

    def _link_sensitivities(self, solver: BDF, compiled: bool) -> None:
        """The sensitivities' arrays and residual (the problem's compiled
        ``c_sensitivities()``, else a callback to its ``sensitivity_residual``)."""
        s, sens, problem = self.s, solver._sens, solver.problem
        p = lambda a: a.ctypes.data if a is not None else None  # noqa: E731
        s.nsens, s.errconS = sens.k, int(sens.errcon)
        s.sphi, s.s_ee, s.s_atol = p(sens.phi), p(sens.ee), p(sens.atol)
        s.s_ewt, s.s_ewt_err, s.s_mask = p(sens.ewt), p(sens.ewt_err), p(sens.mask)
        s.s_res, s.s_delta = p(sens.res), p(sens.delta)
        for a in (sens.y, sens.yp, sens.yy, sens.ypw):
            self._sens_arrays[a.ctypes.data] = a
        own = sens.own
        if own is not None:                 # their own Newton system
            s.s_ab, s.s_cond = p(own.ab), own.cond_ptr
            s.s_ipiv, s.s_prof = p(own.ipiv), p(own.prof)
            self._abs[own.ab.ctypes.data] = own.ab
        get = getattr(problem, "c_sensitivities", None)
        native = get() if (get is not None and compiled) else None
        if native is not None:
            fn, ctx, keep = native
            s.sres, s.sctx = fn, ctx
            self._keep.append(keep)
            return
        n = solver.n
        views = {}
        for a in (sens.y, sens.yp, sens.yy, sens.ypw):
            for i in range(sens.k):
                v = a[i * n:(i + 1) * n]
                views[v.ctypes.data] = v
        state = self._arrays

        def sres(ctx, t, py, pyp, ip, ps, psp, pout):
            problem.sensitivity_residual(t, state[py], state[pyp], ip, views[ps],
                                         views[psp], sens.res)

        cb = SRES_FN(self._guard(sres))
        self._keep.append(cb)
        self._callbacks = True
        s.sres = ctypes.cast(cb, ctypes.c_void_p).value

    #: cells of the Jacobian evaluated per call when it is factored behind its sweep:
    #: the window (JAC_CHUNK + 4 cells of band columns, ~120 kB for the rod) stays in L2
    JAC_CHUNK = 32

    def _jacobian_by_cells(self, jacobian_cells: int, cf: np.ndarray) -> None:
        """Let C evaluate J by cells and factor each cell behind the sweep (``kv_ida``'s
        jac_cells: the full band J is never stored)."""
        s = self.s
        ncell = len(cf) - 1
        k = np.arange(ncell)
        cols = int((cf[np.minimum(k + self.JAC_CHUNK + 4, ncell)] - cf[k]).max())
        win = np.zeros((s.ldab, cols), order="F")
        self._keep.append(win)
        s.jac_cells, s.jwin = jacobian_cells, win.ctypes.data
        s.jwin_cols, s.jchunk = cols, self.JAC_CHUNK

    # -- problem functions -------------------------------------------------------------
    def _guard(self, fn):
        """Run a Python callback for C: 0 on success, 1 after keeping its exception."""
        def call(*args):
            try:
                fn(*args)
                return 0
            except BaseException as exc:  # noqa: BLE001 - re-raised after the C call
                if self._error is None:
                    self._error = exc
                return 1
        return call

    def _set_drive(self, drive) -> None:
        s = self.s

        def go(t: float) -> None:
            s.drive_lo, s.drive_hi = drive(t)

        self._go = go
        cb = DRIVE_FN(self._guard(go))
        self._keep.append(cb)
        s.drive = ctypes.cast(cb, ctypes.c_void_p).value
        s.drive_lo = s.drive_hi = math.nan          # nothing is known to hold yet

    def _python_functions(self, problem) -> None:
        arrays, s = self._arrays, self.s
        ab = self._solver._ab

        def residual(ctx, t, py, pyp, pout):
            problem.residual(t, arrays[py], arrays[pyp], arrays[pout])

        def jacobian(ctx, t, py, pyp, cy, cj, ldab, pab):
            target = self._abs.get(pab, ab)       # the state's or the sensitivities' own
            target.fill(0.0)
            problem.jacobian_band(t, arrays[py], arrays[pyp], cj, target)

        r = RES_FN(self._guard(residual))
        j = JAC_FN(self._guard(jacobian))
        self._keep += [r, j]
        self._callbacks = True
        s.res = ctypes.cast(r, ctypes.c_void_p).value
        s.jac = ctypes.cast(j, ctypes.c_void_p).value
        s.en = None
        s.drive = None
        s.drive_lo, s.drive_hi = -math.inf, math.inf

    # -- state between Python and C ----------------------------------------------------
    _SCALARS = ("kk", "kused", "knew", "ns", "phase", "hh", "hused", "cj", "cjold",
                "cjlast", "cjratio", "ss", "oldnrm", "rr")
    _COUNTERS = ("nstep", "nfev", "njev", "nlu", "nni", "netf", "ncfn")
    _SENS_COUNTERS = ("nfevS", "nniS", "ncfnS", "netfS", "nsetupS")

    def push(self, solver: BDF) -> None:
        """Copy the solver's Python-side state into the struct (at construction and at
        every restart: the energy audit's nodes begin again there)."""
        s = self.s
        s.nh = 0                 # a (re)start: the energy audit's nodes begin again
        for name in self._SCALARS:
            setattr(s, name, getattr(solver, "_" + name))
        s.have_lu = int(solver._have_lu)
        s.t = solver.t
        s.started = solver.t_old is not None
        s.t_old = solver.t_old if solver.t_old is not None else solver.t
        for name in self._COUNTERS:
            setattr(s, name, getattr(solver, name))
        s.nst0 = solver._nst0
        s.t_bound, s.hmax_inv = solver.t_bound, solver._hmax_inv
        sens = solver._sens
        if sens is not None:
            s.s_y, s.s_yp = sens.y.ctypes.data, sens.yp.ctypes.data
            s.s_yy, s.s_ypw = sens.yy.ctypes.data, sens.ypw.ctypes.data
            s.ssS, s.sscaled = sens.ss, int(sens.scaled)
            s.s_cj, s.s_stamp, s.s_have_lu = sens.own_cj, sens.own_stamp, int(sens.own_ok)
            for name in self._SENS_COUNTERS:
                setattr(s, name, getattr(sens, name))
        s.lu_stamp = solver._lu_stamp
        for name in ("psi", "alpha", "beta", "sigma", "gamma"):
            vals = getattr(solver, "_" + name)
            arr = getattr(s, name)
            for k, v in enumerate(vals):
                arr[k] = v

    def pull(self, solver: BDF) -> None:
        """Copy the struct's state back into the solver's attributes (after a C call)."""
        s = self.s
        solver.t = s.t
        solver.t_old = s.t_old if s.started else None
        for name in self._COUNTERS:
            setattr(solver, name, getattr(s, name))
        solver._kused, solver._kk, solver._hh = s.kused, s.kk, s.hh
        solver._psi = list(s.psi)
        a = self._arrays
        solver._y, solver._yp, solver._yy, solver._ypw = a[s.y], a[s.yp], a[s.yy], a[s.ypw]
        solver._fail_index = s.fail_index
        sens = solver._sens
        if sens is not None:
            b = self._sens_arrays
            sens.y, sens.yp, sens.yy, sens.ypw = b[s.s_y], b[s.s_yp], b[s.s_yy], b[s.s_ypw]
            sens.ss, sens.scaled = s.ssS, bool(s.sscaled)
            sens.own_cj, sens.own_stamp, sens.own_ok = s.s_cj, s.s_stamp, bool(s.s_have_lu)
            for name in self._SENS_COUNTERS:
                setattr(sens, name, getattr(s, name))
        solver._lu_stamp = s.lu_stamp

    @property
    def stops_on_signals(self) -> bool:
        """Whether :meth:`advance` returns after the current step when SIGINT or SIGTERM
        arrives (it holds them while the loop may call back into Python, on the main
        thread); otherwise a signal is seen only when the call returns."""
        return self._callbacks and threading.current_thread() is threading.main_thread()

    def advance(self, t_stop: float, max_steps: int) -> int:
        """Run kv_ida_advance and copy the state back into the solver; returns the code
        (``TSTOP`` ...). Re-raises the exception of a callback, then delivers the
        signals held meanwhile (their handlers raise KeyboardInterrupt, Terminated)."""
        self._error = None
        s = self.s
        if s.drive:
            # Python code may have driven the loads to another time since the last call
            # (an observer evaluating the model at an output time): drive them to the
            # current time here, which also tells whether C can need the callback at all
            s.drive_lo = s.drive_hi = s.drive_t = math.nan
            self._go(s.t)
            s.drive_t = s.t
        elif self._drive_now is not None:
            self._drive_now(s.t)             # a no-op unless the model was moved meanwhile
        s.stop = 0
        # the drive is called back only when t leaves [lo, hi) (a release: never again
        # before the end of the run, t_bound)
        drive_calls = bool(s.drive) and not (s.t_bound < s.drive_hi if s.direction > 0
                                              else math.isinf(s.drive_lo))
        if self._callbacks or drive_calls:
            code, held = _call_holding_signals(s, self._lib.kv_ida_advance, self.ptr, t_stop,
                                               max_steps)
        else:
            code, held = self._lib.kv_ida_advance(self.ptr, t_stop, max_steps), ()
        self.pull(self._solver)
        try:
            if self._error is not None:
                exc, self._error = self._error, None
                raise exc
        finally:
            for sig in held:
                signal.raise_signal(sig)
        return code

    # -- audit, samples, watches --------------------------------------------------------
    def enable_audit(self, dissipated: float, external_work: float) -> bool:
        """Integrate 2D and P over every step in C (at the steps' ends, on the polynomial
        through the last ``AUDIT_NODES`` of them:
        ``runtime.simulate.observers.EnergyIntegrator``); False when the problem has no
        compiled energies."""
        if not self.has_energies:
            return False
        s, n = self.s, self._solver.n
        self._wy, self._wyp = np.zeros((2, n)), np.zeros((2, n))
        s.wy, s.wyp = self._wy.ctypes.data, self._wyp.ctypes.data
        s.dissipated, s.external_work = dissipated, external_work
        s.nh = 0
        s.audit = 1
        if self._en_reentrant and not s.nsens and audit_thread_wanted():
            # the ring of the audit's thread: up to 64 slots, at most ~8 MB (taken by
            # the calls during which the loads stay constant: step_loop.c, async_start)
            cap = max(4, min(64, (8 << 20) // (32 * max(n, 1))))
            self._async_buf = np.empty((cap, 4 * n))
            s.async_buf, s.async_cap = self._async_buf.ctypes.data, cap
            s.audit_async = 1
        return True

    #: rows of the sample buffer (handed to ``sink`` whenever full, and at every stop)
    SAMPLE_ROWS = 1024

    def enable_sampling(self, t_out: np.ndarray, k_out: int, indices: np.ndarray,
                        sink, sens_sink=None) -> bool:
        """Record rows ``[t, y[indices]..., T, W, int 2D, int P, extras...]`` at the output
        times ``t_out[k_out:]`` (needs the audit; extras: the energies' values beyond the
        first five, ``CKernels.n_energies``); ``sink(rows)`` receives them (a view: copy
        what you keep) when the buffer is full and at :meth:`flush_samples`. With
        sensitivities, ``sens_sink(rows)`` receives theirs at the same times: rows of
        ``s_i[indices]`` for each parameter i in turn."""
        s = self.s
        if not s.audit:
            return False
        self._t_out = np.ascontiguousarray(t_out, dtype=float)
        self._idx = np.ascontiguousarray(indices, dtype=np.int32)
        self._rec = np.full((self.SAMPLE_ROWS, s.nen + self._idx.size), math.nan)
        self._sink = sink
        self._sy, self._syp = np.zeros(self._solver.n), np.zeros(self._solver.n)
        s.t_out, s.samp_idx, s.rec = (self._t_out.ctypes.data, self._idx.ctypes.data,
                                      self._rec.ctypes.data)
        s.sy, s.syp = self._sy.ctypes.data, self._syp.ctypes.data
        s.nsamp, s.m_out, s.k_out = self._idx.size, self._t_out.size, k_out
        s.rec_w, s.rec_cap, s.rec_n = self._rec.shape[1], self.SAMPLE_ROWS, 0
        cb = DRIVE_FN(self._guard(lambda t: self.flush_samples()))
        self._keep.append(cb)
        self._callbacks = True
        s.flush = ctypes.cast(cb, ctypes.c_void_p).value
        self._ssink = None
        if s.nsens and sens_sink is not None:
            ns = s.nsens * self._solver.n
            self._srec = np.full((self.SAMPLE_ROWS, s.nsens * self._idx.size), math.nan)
            self._s_wy, self._s_wyp = np.zeros(ns), np.zeros(ns)
            s.srec, s.s_wy, s.s_wyp = (self._srec.ctypes.data, self._s_wy.ctypes.data,
                                       self._s_wyp.ctypes.data)
            self._ssink = sens_sink
        return True

    def flush_samples(self) -> None:
        """Hand the buffered sample rows to the sink and empty the buffer."""
        s = self.s
        if s.rec_n:
            self._sink(self._rec[:s.rec_n])
            if self._ssink is not None:
                self._ssink(self._srec[:s.rec_n])
            s.rec_n = 0

    #: bytes of the replay buffer (at least one step's row): at N = 4000 a row (the
    #: history up to order 5) is 2.5 MB
    REPLAY_BYTES = 8 << 20
    #: most rows of the replay buffer
    REPLAY_ROWS = 32

    def enable_replay(self, times: np.ndarray, sink) -> None:
        """Keep the first step reaching each of ``times`` (sorted in the direction of
        integration), and the steps of kept watches (:meth:`set_watches`), for
        ``sink(t_old, t, k, psi, phi, y=y)`` (psi (k+1,), phi (k+1, n): the step's
        interpolant, :meth:`~runtime.solvers.bdf.BDF.dense_output`; y (n,): the state at
        t; views, valid during the call), called in step order when the buffer is full and
        at :meth:`flush_replay`. With sensitivities the sink gets their history too, as a
        sixth argument ``sphi`` (k+1, k_s n)."""
        s, n = self.s, self._solver.n
        self._t_rep = np.ascontiguousarray(times, dtype=float)
        w = 3 + NH + NH * n + NH * s.nsens * n + n          # ... and y at the step's end
        cap = int(max(1, min(self.REPLAY_ROWS, self.REPLAY_BYTES // (8 * w))))
        self._rep = np.zeros((cap, w))
        self._rep_sink = sink
        s.t_rep, s.rep = self._t_rep.ctypes.data, self._rep.ctypes.data
        s.m_rep, s.k_rep, s.rep_w, s.rep_cap, s.rep_n = self._t_rep.size, 0, w, cap, 0
        s.rep_nstep = -1
        cb = DRIVE_FN(self._guard(lambda t: self.flush_replay()))
        self._keep.append(cb)
        self._callbacks = True
        s.rep_flush = ctypes.cast(cb, ctypes.c_void_p).value

    def flush_replay(self) -> None:
        """Hand the kept steps to the sink, in order, and empty the buffer."""
        s = self.s
        if not s.rep_n:
            return
        n, rows = self._solver.n, self._rep[:s.rep_n]
        s.rep_n = 0
        ns = s.nsens * n
        oy = 3 + NH + NH * n + NH * ns
        for row in rows:
            k = int(row[2])
            args = (float(row[0]), float(row[1]), k, row[3:4 + k],
                    row[3 + NH:3 + NH + (k + 1) * n].reshape(k + 1, n))
            if ns:
                o = 3 + NH + NH * n
                args += (row[o:o + (k + 1) * ns].reshape(k + 1, ns),)
            self._rep_sink(*args, y=row[oy:oy + n])

    def enable_grid(self, t_grid: np.ndarray, k: int, out_y: np.ndarray,
                    out_yp: np.ndarray) -> None:
        """Interpolate y and y' at ``t_grid[k:]`` (sorted in the direction of integration)
        into the rows of ``out_y``, ``out_yp`` ((m, n), C order, kept alive by the caller)
        after every step that reaches them, inside the compiled loop; :attr:`grid_done`
        tells how many rows are filled."""
        n = self._solver.n
        for a in (out_y, out_yp):
            if a.shape != (t_grid.size, n) or not a.flags.c_contiguous or a.dtype != float:
                raise ValueError(f"output grid arrays must be C-ordered float ({t_grid.size}, "
                                 f"{n}), got {a.shape}")
        self._t_grid = np.ascontiguousarray(t_grid, dtype=float)
        self._grid = (out_y, out_yp)
        s = self.s
        s.t_grid = self._t_grid.ctypes.data
        s.grid_y, s.grid_yp = out_y.ctypes.data, out_yp.ctypes.data
        s.grid_idx, s.grid_nidx, s.grid_slack = None, 0, 0      # whole states
        s.m_grid, s.k_grid = self._t_grid.size, int(k)

    def enable_frames(self, t_frames: np.ndarray, k: int, indices: np.ndarray,
                      out: np.ndarray) -> bool:
        """Record ``y[indices]`` at ``t_frames[k:]`` (increasing; forward runs) into the
        rows of ``out`` ((m, indices.size), C order, kept alive by the caller) inside the
        compiled loop, with the Centreline observer's rule: a time up to ``1e-12 max(1, abs(t))``
        past a step's end is taken at the end. False (nothing enabled) when the output grid
        is in use or the run goes backwards; :attr:`grid_done` tells the rows filled."""
        s = self.s
        if s.m_grid or s.direction < 0:
            return False
        idx = np.ascontiguousarray(indices, dtype=np.int32).ravel()
        n = self._solver.n
        if (out.shape != (np.size(t_frames), idx.size) or not out.flags.c_contiguous
                or out.dtype != np.float64):
            raise ValueError(f"frame rows must be C-ordered float ({np.size(t_frames)}, "
                             f"{idx.size})")
        if idx.size and not (0 <= idx.min() and idx.max() < n):
            raise ValueError(f"frame components must be state indices 0 ... {n - 1}")
        self._t_grid = np.ascontiguousarray(t_frames, dtype=float)
        self._grid = (out, idx, np.zeros(n))
        s.t_grid, s.grid_y, s.grid_yp = self._t_grid.ctypes.data, out.ctypes.data, None
        s.grid_idx, s.grid_nidx, s.grid_slack = idx.ctypes.data, idx.size, 1
        s.grid_wy = self._grid[2].ctypes.data
        s.m_grid, s.k_grid = self._t_grid.size, int(k)
        return True

    @property
    def grid_done(self) -> int:
        """Rows of the output grid filled so far (:meth:`enable_grid`,
        :meth:`enable_frames`)."""
        return int(self.s.k_grid)

    def set_watches(self, watches: list[tuple[int, float]], kept=()) -> None:
        """Stop after any step in which ``y[index]`` changes sign in ``direction`` (< 0:
        from > 0 to <= 0; > 0: from < 0 to >= 0); or, for the watches flagged in ``kept``
        (booleans, one per watch) while replayed steps are enabled
        (:meth:`enable_replay`), keep such a step for the replay's sink instead."""
        if len(watches) > MAXWATCH:
            raise ValueError(f"at most {MAXWATCH} watched components")
        s = self.s
        s.nwatch = len(watches)
        s.watch_rep = sum(1 << k for k, keep in enumerate(kept) if keep)
        for k, (i, d) in enumerate(watches):
            s.watch_idx[k], s.watch_dir[k] = int(i), float(d)
        self._lib.kv_ida_watch_reset(self.ptr)
