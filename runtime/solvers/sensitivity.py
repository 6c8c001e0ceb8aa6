"""Forward sensitivities of the BDF integration, staggered as in SUNDIALS IDAS (issue 34).

For parameters theta_1 .. theta_k of ``F(t, y, y'; theta) = 0`` the sensitivities
``s_i = dy/dtheta_i`` solve the linear DAEs

    F_y s_i + F_y' s_i' + F_theta_i = 0,

which the problem evaluates exactly (``problem.sensitivity_residual(t, y, yp, i, s, sp,
out)``: the rod's generated tangent, ``runtime/model/native/rod_tangent.c``). IDAS's
staggered corrector (Maderer, Hindmarsh, Serban; ``IDASensNls``): every step of the
state is taken as without sensitivities (the same predictor, corrector, error test, step
and order selection); once the state's corrector has converged and its error test
passed, each sensitivity is predicted from its own BDF history (``phiS``, the same
modified divided differences, rescaled with the state's on step-size and order changes)
and corrected with the state's current iteration matrix ``J = F_y + cj F_y'`` (the same
factorisation, the same Newton system, ``correct``), ``s' = s'_pred + cj (s - s_pred)``.
The system is linear: with the current J one iteration suffices; with an older one the
simplified Newton converges at the rate of ``I - J_old^-1 J``; its convergence test is
the state's (IDA's ``epsNewt``, the rate estimate ``ssS``), but the rate is measured in
every step (at least two iterations unless the first correction is below the
tolerance): a rate carried over from an earlier step, as the state's corrector does,
had accepted first corrections of 5e6 in the weighted norm with an aged matrix (the
cantilever's free end segment at fixed steps), and uncontrolled sensitivities then grew
without bound while the state, whose error test sees its own corrections, was fine.
Where the iteration does not converge within ``maxcor`` iterations J is evaluated
afresh at the converged state and factorised into the sensitivities' own Newton system
(counted: ``nsetupS``), which they then use while it is newer than the state's; the
state's iteration matrix is never touched, so a run with sensitivities takes the plain
run's steps bit for bit. (IDAS refactors the shared matrix instead. A problem whose
Newton system is its own, an assembly's coupled blocks, shares it as IDAS does.) A
second failure is a convergence failure of the step (``ncfnS``: the step is retried
smaller).

Weights: ``ewtS_i = 1 / (rtol |s_i| + atol / pbar_i)`` (IDAS's estimated tolerances,
``pbar_i`` the parameter's size), the norm over the sensitivities the largest of theirs.
With ``errcon`` (IDAS's ``errconS``; off by default) the sensitivities enter the local
error test and the order selection as well, and may change the steps.

The history lives in one array ``phi`` of shape (max order + 2, k n): row j holds the
j-th history vector of every sensitivity, one after the other, so that the predictor,
the history update and the interpolant (``BDFDenseOutput``) are those of a state of
k n unknowns. The compiled step loop (``native/step_loop.c``) does the same, statement
for statement, on the same arrays.
"""

from __future__ import annotations

import math

import numpy as np

#: return flags shared with bdf.py
OK, CONV_FAIL, ERR_FAIL = 0, 1, 2
EPS_NEWT = 0.33
TOL_DEL = 1e-4 * EPS_NEWT
RATE_MAX = 0.9


class StaggeredSensitivities:
    """The sensitivities of one :class:`~runtime.solvers.bdf.BDF` (see the module
    docstring). ``s0``, ``sp0``: consistent initial sensitivities and their rates, (k, n);
    ``pbar``: the parameters' sizes (k,), for the absolute tolerances; ``errcon``: the
    sensitivities in the error test."""

    def __init__(self, solver, s0: np.ndarray, sp0: np.ndarray, pbar: np.ndarray,
                 errcon: bool = False, own=None) -> None:
        n = solver.n
        s0 = np.asarray(s0, dtype=float)
        k = s0.shape[0]
        if s0.shape != (k, n) or np.shape(sp0) != (k, n) or k < 1:
            raise ValueError(f"initial sensitivities must have shape (k, {n}) with k >= 1")
        pbar = np.abs(np.asarray(pbar, dtype=float).ravel())
        if pbar.shape != (k,) or not np.all(pbar > 0.0) or not np.all(np.isfinite(pbar)):
            raise ValueError("pbar: one positive, finite parameter size per sensitivity")
        if not (np.all(np.isfinite(s0)) and np.all(np.isfinite(sp0))):
            raise ValueError("initial sensitivities must be finite")
        self.k, self.n = k, n
        self.nt = k * n
        mo = solver.max_order
        self.phi = np.zeros((mo + 2, self.nt))
        self.y = s0.reshape(-1).copy()
        self.yp = np.asarray(sp0, dtype=float).reshape(-1).copy()
        self.yy = np.empty(self.nt)
        self.ypw = np.empty(self.nt)
        self.ee = np.zeros(self.nt)
        self.res = np.empty(n)
        self.delta = np.empty(self.nt)
        self.pbar = pbar
        self.atol = (np.broadcast_to(solver.atol, (k, n)) / pbar[:, None]).reshape(-1).copy()
        self.ewt = np.empty(self.nt)
        self.mask = None if solver._errmask is None else np.tile(solver._errmask, k)
        self.ewt_err = np.empty(self.nt) if self.mask is not None else self.ewt
        self.errcon = bool(errcon)
        self.ss = 20.0
        self.scaled = False           # phi's rows ns..kk hold phi* (this attempt)
        self.nfevS = self.nniS = self.ncfnS = self.netfS = self.nsetupS = 0
        #: the sensitivities' own Newton system (None: the state's, shared), its cj, the
        #: step count when it was factorised (-1: never) and whether it is regular
        self.own = own
        self.own_cj = 0.0
        self.own_stamp = -1
        self.own_ok = False
        self.update_weights(solver.rtol)

    # -- weights, norms -------------------------------------------------------------------
    def update_weights(self, rtol: float) -> None:
        ewt = self.ewt
        np.abs(self.y, out=ewt)
        ewt *= rtol
        ewt += self.atol
        np.reciprocal(ewt, out=ewt)
        if self.mask is not None:
            np.multiply(ewt, self.mask, out=self.ewt_err)

    def norm(self, solver, v: np.ndarray, w: np.ndarray) -> float:
        """The largest of the sensitivities' weighted RMS norms (IDASensWrmsNorm)."""
        n = self.n
        return max(solver._wrms(v[i * n:(i + 1) * n], w[i * n:(i + 1) * n])
                   for i in range(self.k))

    # -- the history ----------------------------------------------------------------------
    def start_history(self, hh: float) -> None:
        """Order 1 from the current s, s' (as ``BDF._start_history``)."""
        self.phi[0] = self.y
        np.multiply(self.yp, hh, out=self.phi[1])
        self.scaled = False

    def rescale_first(self, factor: float) -> None:
        """The first step's history ``h s'`` to a new h (IDAReset, landing on t_bound)."""
        self.phi[1] *= factor

    def scale(self, solver) -> None:
        """phi -> phi* (IDASetCoeffs' rescaling of rows ns..kk by beta), as the state's."""
        for j in range(solver._ns, solver._kk + 1):
            self.phi[j] *= solver._beta[j]
        self.scaled = True

    def restore(self, solver) -> None:
        """Undo :meth:`scale` after a failed attempt (IDARestore)."""
        if self.scaled:
            for j in range(solver._ns, solver._kk + 1):
                self.phi[j] *= 1.0 / solver._beta[j]
        self.scaled = False

    def predict(self, solver) -> None:
        """IDASensPredict: s = sum_j phi_j, s' = sum_j gamma_j phi_j, summed in j order."""
        phi, yy, ypw = self.phi, self.yy, self.ypw
        np.copyto(yy, phi[0])
        ypw.fill(0.0)
        gamma = solver._gamma
        for j in range(1, solver._kk + 1):
            yy += phi[j]
            ypw += phi[j] * gamma[j]

    # -- the corrector --------------------------------------------------------------------
    def _residuals_and_correct(self, solver, tnew: float, scale: float, cj: float,
                               system) -> float:
        """One Newton iteration of every sensitivity; the largest weighted correction."""
        n, problem = self.n, solver.problem
        correct = system.correct
        exact, exact_res = solver._exact, solver._exact_res
        worst = 0.0
        for i in range(self.k):
            sl = slice(i * n, (i + 1) * n)
            res = self.res
            problem.sensitivity_residual(tnew, solver._yy, solver._ypw, i, self.yy[sl],
                                         self.ypw[sl], res)
            self.nfevS += 1
            if exact.size:
                exact_res[:exact.size] = res[exact]
            ee, yy, ypw = self.ee[sl], self.yy[sl], self.ypw[sl]
            d = correct(res, scale, self.ewt[sl], ee, yy, ypw, cj)
            if exact.size and scale != 1.0:
                for kk, r in enumerate(exact):
                    dd = (1.0 - scale) * exact_res[kk]
                    ee[r] -= dd
                    yy[r] -= dd
                    ypw[r] -= cj * dd
            if not math.isfinite(d):
                return math.inf
            worst = max(worst, d)
        return worst

    def _own_setup(self, solver, tnew: float) -> bool:
        """J at the converged state into the sensitivities' own system, factorised."""
        own = self.own
        own.ab.fill(0.0)
        solver.problem.jacobian_band(tnew, solver._yy, solver._ypw, solver._cj, own.ab)
        self.own_ok = own.factor(solver._cj) == 0
        self.own_cj = solver._cj
        self.own_stamp = solver.nstep
        return self.own_ok

    def nls(self, solver, tnew: float) -> int:
        """IDASensNls: the staggered corrector (see the module docstring); OK or
        CONV_FAIL. Runs after the state's corrector and error test at ``tnew``."""
        if not self.scaled:
            self.scale(solver)
        jcur = False
        while True:
            self.predict(solver)
            self.ee.fill(0.0)
            cj = solver._cj
            mine = self.own is not None and self.own_ok and self.own_stamp >= solver._lu_stamp
            system = self.own if mine else solver._newton
            ratio = cj / self.own_cj if mine else solver._cjratio
            scale = 2.0 / (1.0 + ratio) if ratio != 1.0 else 1.0
            m = 0
            oldnrm = 0.0
            while True:
                delnrm = self._residuals_and_correct(solver, tnew, scale, cj, system)
                self.nniS += 1
                if not math.isfinite(delnrm):
                    break
                if m == 0:
                    oldnrm = delnrm
                    if delnrm <= TOL_DEL:
                        return OK
                else:
                    rate = (delnrm / oldnrm) ** (1.0 / m)
                    if rate > RATE_MAX:
                        break
                    self.ss = rate / (1.0 - rate)
                    if self.ss * delnrm <= EPS_NEWT:
                        return OK
                m += 1
                if m >= solver.max_nonlinear_iter:
                    break
            if jcur:
                self.ncfnS += 1
                return CONV_FAIL
            # J afresh at the converged state, then correct once more
            ok = self._own_setup(solver, tnew) if self.own is not None else solver._setup(tnew)
            self.nsetupS += 1
            if not ok:
                self.ncfnS += 1
                return CONV_FAIL
            self.ss = 20.0
            jcur = True

    def test_error(self, solver, ck: float, err: list[float]) -> int:
        """IDASensTestError: the sensitivities' estimates at orders k, k-1, k-2 raise the
        state's (``err``, updated in place) and may lower the order; OK or ERR_FAIL."""
        kk = solver._kk
        sigma, phi, w = solver._sigma, self.phi, self.ewt_err
        enorm = self.norm(solver, self.ee, w)
        e_k = sigma[kk] * enorm
        check = False
        if e_k > err[0]:
            err[0] = e_k
            check = True
        terr_k = (kk + 1) * err[0]
        if kk > 1:
            d = self.delta
            np.add(phi[kk], self.ee, out=d)
            e_km1 = sigma[kk - 1] * self.norm(solver, d, w)
            if e_km1 > err[1]:
                err[1] = e_km1
                check = True
            terr_km1 = kk * err[1]
            if solver._knew != kk:
                check = False
            if check:
                if kk > 2:
                    d += phi[kk - 1]
                    e_km2 = sigma[kk - 2] * self.norm(solver, d, w)
                    err[2] = max(err[2], e_km2)
                    terr_km2 = (kk - 1) * err[2]
                    if max(terr_km1, terr_km2) <= terr_k:
                        solver._knew = kk - 1
                elif terr_km1 <= 0.5 * terr_k:
                    solver._knew = kk - 1
        if ck * enorm > 1.0:
            self.netfS += 1
            return ERR_FAIL
        return OK

    def order_norm(self, solver, enorm: float) -> float:
        """The estimate at order k+1 with the sensitivities (errcon): the largest norm of
        ``ee - phi_k+1``, the state's ``enorm`` included (IDASensWrmsNormUpdate)."""
        d = self.delta
        np.subtract(self.ee, self.phi[solver._kk + 1], out=d)
        return max(enorm, self.norm(solver, d, self.ewt_err))

    def complete(self, solver, kused: int, rtol: float) -> None:
        """IDACompleteStep's history update for the sensitivities; accept s, s'."""
        phi, ee = self.phi, self.ee
        if kused < solver.max_order:
            np.copyto(phi[kused + 1], ee)
        phi[kused] += ee
        for j in range(kused - 1, -1, -1):
            phi[j] += phi[j + 1]
        self.y, self.yy = self.yy, self.y
        self.yp, self.ypw = self.ypw, self.yp
        self.scaled = False
        self.update_weights(rtol)

    def restart(self, s: np.ndarray, sp: np.ndarray, hh: float, rtol: float) -> None:
        """A restart from consistent s, s' (order 1, a new history)."""
        self.y[:] = np.asarray(s, dtype=float).reshape(-1)
        self.yp[:] = np.asarray(sp, dtype=float).reshape(-1)
        self.update_weights(rtol)
        self.start_history(hh)

    @property
    def counters(self) -> dict[str, int]:
        """nfevS (sensitivity residuals), nniS (their Newton iterations), ncfnS
        (convergence failures of the sensitivities), netfS (their error-test failures,
        errcon), nsetupS (iteration matrices evaluated for them)."""
        return {"nfevS": self.nfevS, "nniS": self.nniS, "ncfnS": self.ncfnS,
                "netfS": self.netfS, "nsetupS": self.nsetupS}
