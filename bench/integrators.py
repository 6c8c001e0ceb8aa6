"""kvrod's BDF against SUNDIALS IDAS (through CasADi) and SciPy at matched accuracy.

The problem is the paper's cantilever (Sect. 5): L = 0.3 m, 1 cm x 1 cm, rho = 1000 kg/m^3,
E = 1 MPa, nu = 0.3, tau_S = tau_B = 0.04 s, clamped at s = 0, free at s = L. The static
equilibrium under a dead tip force of 0.05 N along e1 (``solve_static``, load 0 -> 1) is
released at rest (the load is switched off) and integrated over ``T`` seconds.

Accuracy is the largest tip-x error over an output grid of 100 points per second against
a reference run of kvrod at rtol = atol = 1e-9 (cross-checked against IDAS at 1e-9). Each
integrator gets ``atol = rtol`` (the state is O(0.01..10) in SI units: m, m/s, unit
quaternions, rad/s) and its rtol is scanned in half decades from loose to tight; the
loosest rtol with max tip error <= 1e-5 m is the "matched" run.

How each integrator sees the rod (the residual is linear in y' with a constant diagonal
``D = dF/dy'``: F = D y' + g(t, y); only the clamped node's velocity is algebraic):

- kvrod: ``F(t, y, y') = 0`` and its banded iteration matrix from the compiled kernels
  (ctypes), LAPACK band LU (``runtime.solvers.bdf.BDF``).
- IDAS: CasADi's semi-explicit DAE ``x' = -g_x(t, x, z) / D_x``, ``0 = g_z(t, x, z)``
  (x: differential components in cell-by-cell order, z: the 3 algebraic ones), i.e. the
  same residual with the differential rows divided by the constant ``D``. The DAE function
  is the whole-rod ``RodModel.casadi_residual_function`` (map over the per-cell kernels);
  it and its exact sparse Jacobian (CasADi AD) are code-generated to C once per N and
  loaded with ``casadi.external`` (the library exports ``jac_rod_dae``, so IDAS gets the
  compiled Jacobian); linear solver CSparse (sparse LU). IDAS then runs in C apart from
  CasADi's function-call layer. Alternatives measured by :func:`idas_configs`.
- SciPy ``solve_ivp`` (Radau, BDF): the ODE ``y_d' = -g_d(t, y) / D_d`` on the
  differential components (the algebraic ones are the fixed clamp velocity, 0), compiled
  residual through ctypes, sparse Jacobian ``-D^-1 dg/dy`` (CSC, fixed pattern). Fair up to
  SciPy's per-call Python overhead, which is part of what a SciPy user pays.
"""

from __future__ import annotations

import atexit
import contextlib
import math
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
import scipy.sparse as sp
from scipy.integrate import solve_ivp

from runtime.model import build
from runtime.model.rod import RodModel, RodParameters
from runtime.solvers.integrator import consistent_initial, solve
from runtime.solvers.statics import solve_static

PAPER = {"length": 0.3, "density": 1000.0, "youngs_modulus": 1e6, "poisson_ratio": 0.3,
         "tau_S": 0.04, "tau_B": 0.04, "width": 0.01, "height": 0.01}
TIP_FORCE = (0.05, 0.0, 0.0)
TIP_TOL = 1e-5  # m, matched accuracy: max tip-x error over the run
REF_RTOL = 1e-9
RTOL_SCAN = (1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 3e-8, 1e-8)
OUT_PER_SECOND = 100


# --------------------------------------------------------------------------------------
# The scenario
# --------------------------------------------------------------------------------------


@dataclass
class Cantilever:
    """The released cantilever: model (load_scale 0), consistent (y0, yp0), tip-x index."""

    N: int
    model: RodModel
    y0: np.ndarray
    yp0: np.ndarray
    tip_x: int
    static_seconds: float
    tip_static: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def grid(self, T: float) -> np.ndarray:
        return np.linspace(0.0, T, int(round(OUT_PER_SECOND * T)) + 1)


_CACHE: dict[tuple[int, float | None], Cantilever] = {}
_REFS: dict[tuple[int, float], np.ndarray] = {}  # reference tip x per (N, T)


def cantilever(N: int, tau: float | None = None) -> Cantilever:
    """The paper's cantilever with N elements, statically deflected and released;
    tau (s): tau_S = tau_B = tau instead of PAPER's 0.04 s."""
    if (N, tau) in _CACHE:
        return _CACHE[N, tau]
    par = PAPER if tau is None else {**PAPER, "tau_S": tau, "tau_B": tau}
    model = RodModel(RodParameters(n_elements=N, **par), tip_force=TIP_FORCE)
    t0 = time.perf_counter()
    st = solve_static(model, model.initial_state())
    ts = time.perf_counter() - t0
    model.load_scale = 0.0
    y0, yp0 = consistent_initial(model, 0.0, st.y, np.zeros(model.n))
    tip_x = int(model.tip_position(np.arange(model.n, dtype=float))[0])
    c = Cantilever(N, model, y0, yp0, tip_x, ts, model.tip_position(st.y))
    _CACHE[N, tau] = c
    return c


def _best_of(fn, budget: float = 1.0, repeat: int = 3) -> tuple[float, Any]:
    """Run fn() (returns a result); repeat while cheap, keep the best wall time."""
    t0 = time.perf_counter()
    out = fn()
    best = time.perf_counter() - t0
    for _ in range(repeat - 1):
        if best > budget:
            break
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def tip_error(tip: np.ndarray, ref: np.ndarray) -> float:
    return float(np.max(np.abs(np.asarray(tip) - ref)))


# --------------------------------------------------------------------------------------
# kvrod
# --------------------------------------------------------------------------------------


def run_kvrod(c: Cantilever, T: float, rtol: float, **options: Any) -> dict:
    """kvrod's BDF on the cantilever: wall time, counters, tip x on the output grid."""
    grid = c.grid(T)

    def go():
        return solve(c.model, (0.0, T), c.y0, c.yp0, rtol=rtol, atol=rtol, t_eval=grid,
                     **options)

    wall, s = _best_of(go)
    if not s.success:
        return {"integrator": "kvrod", "rtol": rtol, "ok": False, "message": s.message,
                "wall": wall}
    k = s.counters
    return {"integrator": "kvrod", "rtol": rtol, "ok": True, "wall": wall,
            "steps": k["nstep"], "nfev": k["nfev"], "njev": k["njev"], "nlu": k["nlu"],
            "nni": k["nni"], "netf": k["netf"], "ncfn": k["ncfn"], "tip": s.y[c.tip_x]}


# --------------------------------------------------------------------------------------
# IDAS through CasADi
# --------------------------------------------------------------------------------------


@dataclass
class IdasDae:
    """The cantilever as CasADi's semi-explicit DAE (see module docstring)."""

    dae: ca.Function
    x_idx: np.ndarray
    z_idx: np.ndarray
    build_seconds: float
    how: str
    detail: str = ""


def _dae_function(c: Cantilever) -> tuple[ca.Function, np.ndarray, np.ndarray]:
    m = c.model
    Ff = m.casadi_residual_function()
    D = m.dF_dyp_sparse(0.0, c.y0, c.yp0).diagonal()
    di, ai = np.nonzero(m.differential)[0], np.nonzero(~m.differential)[0]
    if np.any(D[di] == 0) or np.any(D[ai] != 0):
        raise RuntimeError("dF/dy' is not the expected constant diagonal")
    t = ca.MX.sym("t")
    x, z = ca.MX.sym("x", di.size), ca.MX.sym("z", ai.size)
    inv = np.argsort(np.concatenate([di, ai]))
    y = ca.vertcat(x, z)[inv.tolist()]
    g = Ff(t, y, ca.DM.zeros(m.n))
    ode = -g[di.tolist()] / ca.DM(D[di])
    alg = g[ai.tolist()]
    p, u = ca.MX.sym("p", 0), ca.MX.sym("u", 0)
    f = ca.Function("rod_dae", [t, x, z, p, u], [ode, alg, ca.MX(0, 1), ca.MX(0, 1)],
                    ca.dyn_in(), ca.dyn_out())
    return f, di, ai


def idas_dae(c: Cantilever, how: str = "jit", workdir: Path | None = None) -> IdasDae:
    """Build the DAE for IDAS.

    "jit": the MX function; the integrator jit-compiles the functions it derives (residual,
    sparse Jacobian) with gcc -O2 (compiles cached by source hash). "external": the DAE
    and its full Jacobian code-generated and compiled here, loaded by casadi.external.
    "mx": CasADi's MX virtual machine over the kernel map. "expand": SX virtual machine.
    """
    t0 = time.perf_counter()
    f, di, ai = _dae_function(c)
    detail = ""
    if how == "external":
        cc = build.find_compiler()
        if cc is None:
            raise RuntimeError("no C compiler for the IDAS external DAE")
        wd = Path(workdir or tempfile.mkdtemp(prefix="kvrod_idas_"))
        cg = ca.CodeGenerator("rod_dae.c")
        cg.add(f)
        cg.add(f.jacobian())  # exported as jac_rod_dae, picked up by casadi.external
        cg.generate(str(wd) + "/")
        t1 = time.perf_counter()
        so = wd / f"rod_dae_{c.N}.so"
        subprocess.run([cc, "-O2", "-fPIC", "-shared", str(wd / "rod_dae.c"), "-o", str(so),
                        "-lm"], check=True, capture_output=True)
        dae = ca.external("rod_dae", str(so))
        detail = f"codegen {t1 - t0:.1f} s, gcc {time.perf_counter() - t1:.1f} s"
    elif how == "expand":
        dae = f.expand()
    elif how in ("mx", "jit"):
        dae = f
    else:
        raise ValueError(f"how must be 'external', 'mx' or 'expand', got {how!r}")
    return IdasDae(dae, di, ai, time.perf_counter() - t0, how, detail)


_CC_CACHE = """#!/bin/sh
# CasADi's shell-compiler call "cc FLAGS -c SRC -o OBJ" (or a link step), cached by the
# SHA-256 of SRC: an integrator rebuilt for another rtol generates the same C.
src=""; obj=""; prev=""
for a in "$@"; do
  [ "$prev" = "-c" ] && src="$a"
  [ "$prev" = "-o" ] && obj="$a"
  prev="$a"
done
case "$src" in *.c) ;; *) exec {cc} "$@" ;; esac
key=$(cat "$src" | sha256sum | cut -c1-32)
if [ -f "{dir}/$key.o" ]; then cp "{dir}/$key.o" "$obj"; exit 0; fi
{cc} "$@" && cp "$obj" "{dir}/$key.o"
"""
_JIT_DIR: Path | None = None


def _jit_options() -> dict:
    """CasADi integrator options to jit-compile its DAE functions (gcc -O2, cached)."""
    global _JIT_DIR
    cc = build.find_compiler()
    if cc is None:
        raise RuntimeError("no C compiler for CasADi's jit")
    if _JIT_DIR is None:
        _JIT_DIR = Path(tempfile.mkdtemp(prefix="kvrod_jit_"))
        atexit.register(shutil.rmtree, _JIT_DIR, True)
        script = _JIT_DIR / "cc_cache.sh"
        script.write_text(_CC_CACHE.replace("{cc}", cc).replace("{dir}", str(_JIT_DIR)))
        script.chmod(0o755)
    return {"jit": True, "compiler": "shell", "jit_temp_suffix": False,
            "jit_options": {"compiler": str(_JIT_DIR / "cc_cache.sh"), "linker": cc,
                            "flags": ["-O2"], "directory": str(_JIT_DIR) + "/"}}


def run_idas(c: Cantilever, dae: IdasDae, T: float, rtol: float,
             linear_solver: str = "csparse") -> dict:
    """IDAS (CasADi 'idas') on the cantilever at rtol = abstol = rtol."""
    grid = c.grid(T)
    opts = {"reltol": rtol, "abstol": rtol, "linear_solver": linear_solver,
            "max_num_steps": 10**8, "calc_ic": False, "disable_internal_warnings": True}
    t0 = time.perf_counter()
    if dae.how == "jit":
        opts.update(_jit_options())
        with contextlib.chdir(_JIT_DIR):  # CasADi writes the jit source to the cwd
            integ = ca.integrator("I", "idas", dae.dae, 0.0, grid[1:].tolist(), opts)
    else:
        integ = ca.integrator("I", "idas", dae.dae, 0.0, grid[1:].tolist(), opts)
    t_setup = time.perf_counter() - t0
    x0, z0 = c.y0[dae.x_idx], c.y0[dae.z_idx]
    name = f"idas ({dae.how}, {linear_solver})"
    try:
        wall, r = _best_of(lambda: integ(x0=x0, z0=z0))
    except RuntimeError as exc:
        return {"integrator": name, "rtol": rtol, "ok": False, "message": str(exc)[-300:]}
    st = integ.stats()
    xf = np.asarray(r["xf"])
    k = int(np.nonzero(dae.x_idx == c.tip_x)[0][0])
    tip = np.concatenate([[c.y0[c.tip_x]], xf[k]])
    nls = int(st.get("nlinsetups", 0))
    return {"integrator": name, "rtol": rtol, "ok": True, "wall": wall,
            "setup_seconds": t_setup, "steps": int(st.get("nsteps", 0)),
            "nfev": int(st.get("nfevals", 0)), "njev": nls, "nlu": nls,
            "nni": int(st.get("nniters", 0)), "netf": int(st.get("netfails", 0)),
            "ncfn": int(st.get("nncfails", 0)), "tip": tip}


# --------------------------------------------------------------------------------------
# SciPy solve_ivp on the ODE form
# --------------------------------------------------------------------------------------


class OdeForm:
    """y_d' = -g_d(t, y)/D_d on the differential components (algebraic ones fixed)."""

    def __init__(self, c: Cantilever) -> None:
        m = self.model = c.model
        self.di = np.nonzero(m.differential)[0]
        self.D = m.dF_dyp_sparse(0.0, c.y0, c.yp0).diagonal()[self.di]
        self.y = c.y0.copy()  # algebraic entries stay at their consistent values
        self.zero = np.zeros(m.n)
        self.res = np.empty(m.n)
        self.nfev = self.njev = 0
        self._sel = sp.diags(-1.0 / self.D) @ sp.eye(m.n, format="csr")[self.di]

    def rhs(self, t: float, yd: np.ndarray) -> np.ndarray:
        self.nfev += 1
        self.y[self.di] = yd
        self.model.residual(t, self.y, self.zero, self.res)
        return -self.res[self.di] / self.D

    def jac(self, t: float, yd: np.ndarray) -> sp.csc_matrix:
        self.njev += 1
        self.y[self.di] = yd
        J = self.model.dF_dy_sparse(t, self.y, self.zero)
        return (self._sel @ J[:, self.di]).tocsc()


def run_scipy(c: Cantilever, T: float, rtol: float, method: str) -> dict:
    grid = c.grid(T)

    def go():
        ode = OdeForm(c)
        sol = solve_ivp(ode.rhs, (0.0, T), c.y0[ode.di], method=method, t_eval=grid,
                        rtol=rtol, atol=rtol, jac=ode.jac)
        return ode, sol

    wall, (ode, sol) = _best_of(go, repeat=1)
    name = f"scipy {method}"
    if not sol.success:
        return {"integrator": name, "rtol": rtol, "ok": False, "message": sol.message,
                "wall": wall}
    k = int(np.nonzero(ode.di == c.tip_x)[0][0])
    return {"integrator": name, "rtol": rtol, "ok": True, "wall": wall,
            "steps": None, "nfev": int(sol.nfev),
            "njev": int(sol.njev), "nlu": int(sol.nlu), "tip": sol.y[k]}


# --------------------------------------------------------------------------------------
# Matched accuracy
# --------------------------------------------------------------------------------------


def matched(runner, ref: np.ndarray, rtols=RTOL_SCAN, budget: float = math.inf,
            start: float | None = None) -> dict:
    """The loosest rtol of the scan with max tip error <= TIP_TOL, and the runs made.

    Without ``start``: from loose to tight, stopping at the first pass. With ``start`` (an
    rtol of the scan, e.g. another integrator's match): from there looser while it
    passes, or tighter until it passes. A run slower than ``budget`` s ends the scan.
    """
    rtols = list(rtols)
    scan: list[dict] = []

    def attempt(rtol: float) -> dict:
        r = runner(rtol)
        if r.get("ok"):
            r["tip_error"] = tip_error(r["tip"], ref)
        entry = {k: v for k, v in r.items() if k != "tip"}
        entry["pass"] = bool(r.get("ok") and r["tip_error"] <= TIP_TOL)
        scan.append(entry)
        return entry

    if start is None or start not in rtols:
        order = rtols
    else:
        i0 = rtols.index(start)
        e = attempt(start)
        if e["pass"]:
            best = e
            for rtol in reversed(rtols[:i0]):
                e = attempt(rtol)
                if not e["pass"]:
                    break
                best = e
            return {"matched": best, "scan": scan}
        if e.get("wall", 0.0) > budget:
            return {"matched": None, "scan": scan}
        order = rtols[i0 + 1:]
    for rtol in order:
        e = attempt(rtol)
        if e["pass"]:
            return {"matched": e, "scan": scan}
        if e.get("wall", 0.0) > budget:
            break
    return {"matched": None, "scan": scan}


def compare(N: int, T: float, scipy_methods=("BDF", "Radau"), idas_how: str = "jit",
            scipy_budget: float = 60.0, log=print) -> dict:
    """Reference, cross-check, and the matched-accuracy runs of every integrator for N."""
    c = cantilever(N)
    ref_run = run_kvrod(c, T, REF_RTOL)
    ref = _REFS[(N, T)] = ref_run["tip"]
    dae = idas_dae(c, idas_how)
    log(f"  N={N}: reference {ref_run['wall']:.2f} s; IDAS DAE ({idas_how}) built in "
        f"{dae.build_seconds:.1f} s")
    out: dict[str, Any] = {"N": N, "n": c.model.n, "T": T, "static_seconds": c.static_seconds,
                           "reference": {k: v for k, v in ref_run.items() if k != "tip"},
                           "idas_build_seconds": dae.build_seconds, "idas_how": idas_how}
    idas_ref = run_idas(c, dae, T, REF_RTOL)
    out["idas_first_setup_seconds"] = idas_ref.get("setup_seconds")  # jit: includes gcc
    out["cross_check"] = {"idas_rtol": REF_RTOL, "idas_wall": idas_ref.get("wall"),
                          "max_tip_diff": tip_error(idas_ref["tip"], ref)
                          if idas_ref.get("ok") else None}
    out["kvrod"] = matched(lambda r: run_kvrod(c, T, r), ref)
    log(f"  N={N}: kvrod {_fmt(out['kvrod'])}")
    start = out["kvrod"]["matched"]["rtol"] if out["kvrod"]["matched"] else None
    out["idas"] = matched(lambda r: run_idas(c, dae, T, r), ref, start=start)
    log(f"  N={N}: IDAS  {_fmt(out['idas'])}")
    for method in scipy_methods:
        key = f"scipy_{method.lower()}"
        out[key] = matched(lambda r, m=method: run_scipy(c, T, r, m), ref,
                           budget=scipy_budget)
        log(f"  N={N}: SciPy {method} {_fmt(out[key])}")
    a, b = out["kvrod"]["matched"], out["idas"]["matched"]
    out["ratio_kvrod_over_idas"] = a["wall"] / b["wall"] if a and b else None
    return out


def _fmt(m: dict) -> str:
    r = m["matched"]
    if r is None:
        return "no rtol in the scan reached the accuracy"
    return f"rtol {r['rtol']:.0e}: {r['wall']:.3f} s, {r['steps']} steps, err {r['tip_error']:.1e}"


def idas_configs(N: int, T: float, rtol: float,
                 jit_compile_seconds: float | None = None) -> list[dict]:
    """IDAS wall time per DAE build ("jit", "external", "expand", "mx") and linear solver
    (CSparse LU; CasADi's default "qr") at one rtol. (Also tried by hand: MUMPS, 1.6x
    slower than CSparse here; MA27 needs HSL, not shipped; "ldl" needs symmetry.)

    For "jit" the compile is cached when :func:`compare` ran first for this N; pass its
    first integrator set-up time as ``jit_compile_seconds`` to report it.
    """
    c = cantilever(N)
    if (N, T) not in _REFS:
        _REFS[(N, T)] = run_kvrod(c, T, REF_RTOL)["tip"]
    ref = _REFS[(N, T)]
    rows = []
    for how, linsol in (("jit", "csparse"), ("jit", "qr"), ("external", "csparse"),
                        ("expand", "csparse"), ("mx", "csparse")):
        dae = idas_dae(c, how)
        r = run_idas(c, dae, T, rtol, linear_solver=linsol)
        row = {"how": f"{how}, {linsol}", "build_seconds": dae.build_seconds,
               "detail": dae.detail, **{k: v for k, v in r.items() if k != "tip"}}
        if r.get("ok"):
            row["tip_error"] = tip_error(r["tip"], ref)
        if how == "jit" and linsol == "csparse" and jit_compile_seconds is not None:
            row["setup_seconds"] = jit_compile_seconds
        rows.append(row)
    return rows


# --------------------------------------------------------------------------------------
# Where kvrod's time goes
# --------------------------------------------------------------------------------------


class _Timer:
    """Accumulated wall time and calls of the wrapped callables (by name)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self.calls: dict[str, int] = {}

    def wrap(self, name: str, fn):
        self.seconds.setdefault(name, 0.0)
        self.calls.setdefault(name, 0)
        clock = time.perf_counter

        def timed(*args):
            t0 = clock()
            out = fn(*args)
            self.seconds[name] += clock() - t0
            self.calls[name] += 1
            return out

        return timed


class _TimedProblem:
    def __init__(self, model: RodModel, timer: _Timer) -> None:
        self.n, self.kl, self.ku = model.n, model.kl, model.ku
        self.differential = model.differential
        self.residual = timer.wrap("residual", model.residual)
        self.jacobian_band = timer.wrap("jacobian", model.jacobian_band)


class _TimedLib:
    def __init__(self, lib, timer: _Timer) -> None:
        self.kv_gbtrf = timer.wrap("lu", lib.kv_gbtrf)
        self.kv_newton = timer.wrap("newton_solve_update", lib.kv_newton)
        self.kv_wrms = timer.wrap("norms", lib.kv_wrms)


def breakdown(N: int, T: float, rtol: float) -> dict:
    """Split kvrod's wall time into residual, Jacobian, LU, Newton solves (band solve and
    updates, in C), norms and the rest (the integrator's Python: coefficients,
    predictor, error test, history update). Output handling is left out (no t_eval)."""
    from runtime.solvers.bdf import BDF

    c = cantilever(N)
    timer = _Timer()
    prob = _TimedProblem(c.model, timer)
    t0 = time.perf_counter()
    s = BDF(prob, 0.0, c.y0, c.yp0, T, rtol=rtol, atol=rtol)
    if s._c is not None:
        s._c = _TimedLib(s._c, timer)
    else:
        timer.seconds["lu"] = timer.seconds["newton_solve_update"] = 0.0
    while s.status == "running":
        s.step()
    total = time.perf_counter() - t0
    parts = dict(timer.seconds)
    parts["python_integrator"] = total - sum(parts.values())
    return {"N": N, "T": T, "rtol": rtol, "total": total, "seconds": parts,
            "calls": timer.calls, "counters": s.counters,
            "note": "timer wrappers add about 0.3 us per call to the totals"}
