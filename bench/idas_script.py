"""The strong SUNDIALS opponent: IDAS (or CVODES) on kvrod's rod, compiled flat.

``python -m bench.idas_script --n-elements 50 --t-end 10 --rtol 1e-6`` is a whole process
that does what a strong CasADi user would do with kvrod's rod, and prints the tip maxima
(t, x), the integration time and the step count:

1. the paper's cantilever (``load_problem("cantilever")``, ``build_model``) and its static
   deflection under the tip force (kvrod's ``static_equilibrium``); the force is then
   released (``model.at(0.0)``) and the consistent (y0, y0') taken from
   ``consistent_initial``; ``--problem`` takes another built-in name or TOML file of that
   kind, e.g. ``examples/maxwell_cantilever.toml`` (a generalized Maxwell rod: its
   internal strains are state entries, released relaxed; by default, as kvrod, its
   velocities are out of the error test, ``--error-control``; :mod:`bench.maxwell`);
2. the rod's residual F(t, y, y') from :class:`runtime.model.casadi_oracle.CasadiOracle` (MX over
   the per-element kernels) with the released arrays as constants, expanded to SX;
3. the **ODE form** (the default): F is linear in y' with a constant diagonal D = dF/dy'
   (F = D y' + g(t, y)) and only the clamped node's velocity is algebraic (and constant,
   0), so the differential components obey the explicit ODE y_d' = -g_d(t, y)/D_d. The
   state is scaled per component, x = s * xi with s the per-field scales of kvrod's
   default absolute tolerances (``default_atol``), so that a scalar absolute tolerance
   on xi is a per-component one on y (CVODES through CasADi takes only a scalar
   ``abstol``); IDAS also gets the per-component values through ``abstolv``. The
   **DAE form** keeps the 3 algebraic rows (semi-explicit: x' = -g_x/D_x, 0 = g_z);
4. that function and its exact sparse Jacobian (CasADi AD on the SX graph, no MX calls
   inside) generated as one C file and compiled with ``gcc -O2 -march=native`` into one
   shared library, cached by a hash of everything the code depends on (the generated
   kernels, the rod's arrays, the form, CasADi's version, compiler and flags) in
   ``$KVROD_CACHE_DIR/bench-idas`` (else the user cache dir); a cached library is loaded
   with ``casadi.external`` without rebuilding anything;
5. IDAS (``casadi.integrator(..., "idas", ...)``) with CSparse's sparse LU, rtol and the
   per-component atol (default: ``default_atol``, the tolerances ``kvrod simulate``
   uses; ``--atol A`` a scalar), the initial derivative from step 1 (``init_xdot``, so no
   ``IDACalcIC``), outputs every ``output_step`` (as ``kvrod simulate``); tip maxima from
   the outputs by cubic Hermite interpolation of (x, x') between samples.

The flat C grows with N: 5.5 MB at N = 50 (gcc about 45 s), 22 MB at N = 200 (gcc
255-340 s, 3.8 GB of memory); N = 1000 (~110 MB) is beyond a small machine. For large N,
``--build kernels`` gives SUNDIALS kvrod's own compiled residual and banded Jacobian
(``bench/idas_kernels.c`` behind CasADi's external-function API, one library for every N,
compiled in about 1 s; per step as fast as flat at N = 50, faster from N = 200), so that
the comparison measures the integrators and their linear algebra on equal functions.
Other variants for the benchmark tables (see :func:`build_function`): "map" (the MX
function over the kernel maps, generated to C: its MX Jacobian is slow), "sx" (SX virtual
machine, no compile), "mx" (MX virtual machine). The benchmarks
(:mod:`bench.integrators`) import this module.

Whole-process timing of this script against ``kvrod simulate`` (medians over runs; for
example with ``/usr/bin/time`` or hyperfine)::

    python -m bench.idas_script --n-elements 50 --t-end 10
    python -m kvrod simulate cantilever --n-elements 50 --t-end 10 --out /tmp/x --overwrite
"""

from __future__ import annotations

import argparse
import atexit
import ctypes
import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from runtime import native
from runtime.errors import ParameterError
from runtime.model import build
from runtime.problem.assemble import build_model
from runtime.problem.registry import ProblemFileError, load_problem
from runtime.simulate.simulate import default_atol, static_equilibrium
from runtime.solvers.integrator import consistent_initial

#: bump when the generated functions change for the same inputs (invalidates the cache)
BUILDER_VERSION = "1"
CFLAGS = ("-O2", "-march=native", "-fPIC", "-shared")
#: the kernels build gets the flags kvrod compiles the same kernels with (runtime/model/
#: build.py): equal functions on both sides (the flat build keeps -O2: straight-line C of
#: megabytes gains nothing from -O3 and compiles for minutes)
KERNEL_CFLAGS = ("-O3", "-march=native", "-fno-semantic-interposition", "-ffp-contract=off",
                 "-fPIC", "-shared")
FORMS = ("ode", "dae")
BUILDS = ("flat", "kernels", "map", "sx", "mx")
ERROR_CONTROLS = ("state", "configuration")
#: factor on the absolute tolerances of the velocities (and, for CVODES, on their scaling)
#: that takes them out of the error test: their weights 1/(rtol |y| + atol) become ~1e-12
#: of the others' (a power of two, so the scaling is exact in floating point)
OUT_OF_TEST = 2.0**40
KERNELS_C = Path(__file__).resolve().with_name("idas_kernels.c")


# --------------------------------------------------------------------------------------
# The released rod
# --------------------------------------------------------------------------------------


@dataclass
class ReleasedRod:
    """A rod after release (by default the paper's cantilever): model (tip load off),
    consistent (y0, yp0), the constant diagonal D of dF/dy', differential/algebraic
    indices, tip indices, and the per-field tolerance scales ``scale`` (atol = rtol *
    scale for rtol >= 1e-8)."""

    problem: Any
    model: Any
    y0: np.ndarray
    yp0: np.ndarray
    D: np.ndarray
    di: np.ndarray
    ai: np.ndarray
    tip_x: int
    tip_vx: int
    scale: np.ndarray
    static_seconds: float
    static_y: np.ndarray

    @property
    def N(self) -> int:
        return int(self.model.N)

    @property
    def n(self) -> int:
        return int(self.model.n)

    def atol(self, rtol: float) -> np.ndarray:
        """kvrod's default absolute tolerances (n,) at this rtol (``default_atol``)."""
        p = self.problem.with_overrides({"rtol": rtol})
        return default_atol(p, self.model, self.static_y)

    @property
    def velocity_mask(self) -> np.ndarray:
        """(n,) bool: the velocities (node v, segment Omega), which kvrod's default error
        test leaves out for a generalized Maxwell rod (``RodModel.velocity_mask``)."""
        return self.model.velocity_mask

    def default_error_control(self) -> str:
        """What ``kvrod simulate`` controls on this problem by default: "configuration"
        for a generalized Maxwell rod, "state" otherwise (``Problem.error_control``)."""
        return self.problem.error_control()


def released_rod(n_elements: int | None = None, t_end: float | None = None,
                 rtol: float = 1e-6, overrides: dict | None = None,
                 problem: str | Path = "cantilever") -> ReleasedRod:
    """A problem (default the paper's cantilever; a built-in name or a TOML file) with
    ``n_elements`` (default: the problem's), deflected statically and released (its
    loads at t = 0-, then at t = 0 from the right: the released tip load is off).

    As ``kvrod simulate`` with ``initial = "static"``: the relaxation terms of a
    generalized Maxwell rod start relaxed (``RodModel.relaxed``: the load was held long
    enough; the identity for Kelvin-Voigt). The ODE form needs F linear in y' with a
    constant diagonal dF/dy' (node masses and inertias, 1 on the kinematic rows and on the
    internal strains' rows q' - (strain - q)/theta), zero on the algebraic rows, and the
    held nodes at rest: checked here."""
    ov: dict[str, Any] = {}
    if n_elements is not None:
        ov["n_elements"] = int(n_elements)
    if t_end is not None:
        ov["t_end"] = t_end
    problem = load_problem(problem, {**ov, "rtol": rtol, **(overrides or {})})
    model = build_model(problem)
    t0 = time.perf_counter()
    st = static_equilibrium(problem, model)
    ts = time.perf_counter() - t0
    model.at(0.0)          # dynamic from t = 0: the released tip load is off
    zero = np.zeros(model.n)
    y0, yp0 = consistent_initial(model, 0.0, model.relaxed(st.y), zero)
    D = model.dF_dyp_sparse(0.0, y0, yp0).diagonal()
    di, ai = np.nonzero(model.differential)[0], np.nonzero(~model.differential)[0]
    if np.any(D[di] == 0) or np.any(D[ai] != 0):
        raise RuntimeError("dF/dy' is not the expected constant diagonal (zero on the "
                           "algebraic rows only)")
    if np.any(yp0[ai] != 0) or model.drive is not None and _moves(problem):
        raise RuntimeError("the ODE form needs held nodes at rest (no prescribed motion)")
    scale = default_atol(problem.with_overrides({"rtol": 1e-6}), model, st.y) / 1e-6
    ix, iv = int(model.phi_index[-1][0]), int(model.v_index[-1][0])
    return ReleasedRod(problem, model, y0, yp0, D, di, ai, ix, iv, scale, ts, st.y)


def _moves(problem) -> bool:
    return any(e.motion is not None for e in (problem.start, problem.end))


# --------------------------------------------------------------------------------------
# The CasADi function (ODE or DAE form) and its compiled library
# --------------------------------------------------------------------------------------


@dataclass
class Opponent:
    """A CasADi DAE function in the integrator's signature (t, x, z, p, u) -> (ode, alg,
    quad, zero) for one rod, form and build, and how it was made."""

    fn: ca.Function
    form: str
    build: str
    xs: np.ndarray            # state indices of x (then z for the DAE form)
    s: np.ndarray             # scaling of x: y[xs] = s * x
    zs: np.ndarray
    seconds: dict[str, float] = field(default_factory=dict)
    cached: bool = False
    c_bytes: int = 0
    library: str = ""
    keep: Any = None          # what the compiled code points into (build "kernels")
    #: the scaling's error control: "configuration" multiplies the velocities' scales by
    #: OUT_OF_TEST (CVODES's scalar abstol then leaves them out of its error test)
    error_control: str = "state"

    @property
    def label(self) -> str:
        ec = "" if self.error_control == "state" else ", velocities scaled out"
        return f"{self.form}, {self.build}{ec}"


def _scales(rod: ReleasedRod, form: str, error_control: str) -> np.ndarray:
    """The ODE form's scaling s of x (y[di] = s * x): kvrod's default atol per unit rtol,
    times OUT_OF_TEST on the velocities for ``error_control = "configuration"``; ones
    for the DAE form."""
    if form != "ode":
        return np.ones(rod.di.size)
    s = rod.scale[rod.di].copy()
    if error_control == "configuration":
        s[rod.velocity_mask[rod.di]] *= OUT_OF_TEST
    return s


def _cache_key(rod: ReleasedRod, form: str, build_kind: str, cc: str,
               error_control: str = "state") -> str:
    h = hashlib.sha256()
    gdir = build.generated_dir()
    h.update((gdir / "MANIFEST.json").read_bytes())
    a = rod.model.arrays
    for arr in (a.par, a.seg, a.jnt, a.nload, a.sload, rod.D, rod.scale,
                rod.y0[rod.ai], rod.di.astype(np.int64)):
        h.update(np.ascontiguousarray(arr).tobytes())
    if a.branches:      # relaxation terms (a Kelvin-Voigt rod's key is unchanged)
        for arr in (a.theta, a.segb, a.jntb):
            h.update(np.ascontiguousarray(arr).tobytes())
    meta = [BUILDER_VERSION, form, build_kind, ca.__version__, cc, *CFLAGS,
            str(a.held("start")), str(a.held("end")), str(a.clamped("start")),
            str(a.clamped("end"))]
    if error_control != "state":
        meta.append(f"{error_control} {OUT_OF_TEST!r}")
    h.update("\0".join(meta).encode())
    return h.hexdigest()[:32]


def _symbolic(rod: ReleasedRod, form: str, sym,
              error_control: str = "state") -> tuple[Any, ...]:
    """(t, x, z, ode, alg, xs, s, zs) in SX or MX (``sym``) with the arrays as constants."""
    from runtime.model.casadi_oracle import CasadiOracle

    m = rod.model
    cr = CasadiOracle(m.arrays)
    res = cr.residual.expand() if sym is ca.SX else cr.residual
    args = [ca.DM(np.asarray(v)) for v in CasadiOracle.args(m.arrays)]
    t = sym.sym("t")
    di, ai = rod.di, rod.ai
    if form == "ode":
        s = _scales(rod, form, error_control)
        x = sym.sym("x", di.size)
        z = sym.sym("z", 0)
        parts = [x * ca.DM(s), ca.DM(rod.y0[ai])]
    else:
        s = np.ones(di.size)
        x, z = sym.sym("x", di.size), sym.sym("z", ai.size)
        parts = [x, z]
    inv = np.argsort(np.concatenate([di, ai]))
    y = ca.vertcat(*parts)[inv.tolist()]
    g = res(t, y, ca.DM.zeros(m.n), *args)
    ode = -g[di.tolist()] / ca.DM(rod.D[di] * s)
    alg = g[ai.tolist()] if form == "dae" else sym(0, 1)
    return t, x, z, ode, alg, di, s, (ai if form == "dae" else np.zeros(0, dtype=int))


def _cache_dir(cache_dir: Path | None) -> Path:
    return Path(cache_dir or os.environ.get("KVROD_BENCH_IDAS_CACHE")
                or native.cache_dir() / "bench-idas")


def _compile(cc: str, sources: list[Path], so: Path, include: list[str] | None = None,
             flags: tuple[str, ...] = CFLAGS) -> float:
    """gcc the sources into ``so`` (atomically: temporary name, then rename); seconds."""
    so.parent.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(dir=so.parent, prefix="build_") as tmp:
        out = Path(tmp) / so.name
        inc = list(include or [])
        subprocess.run([cc, *flags, *inc, *map(str, sources), "-o", str(out), "-lm"],
                       check=True, capture_output=True)
        os.replace(out, so)
    return time.perf_counter() - t0


def kernels_library(cache_dir: Path | None = None) -> tuple[Path, float, bool]:
    """The compiled ``bench/idas_kernels.c`` with kvrod's generated C (one library for
    every N; cached by the sources' hash): (path, compile seconds, was cached)."""
    cc = native.find_compiler()
    if cc is None:
        raise RuntimeError("no C compiler for the IDAS kernels build")
    gdir = build.generated_dir()
    sources = [KERNELS_C, *build.source_paths(gdir)]
    h = hashlib.sha256()
    for f in (*sources, *build.header_paths(gdir)):
        h.update(f.read_bytes())
    h.update("\0".join([BUILDER_VERSION, cc, *KERNEL_CFLAGS, native.host_id()]).encode())
    so = _cache_dir(cache_dir) / f"rod_ode_kernels_{h.hexdigest()[:32]}.so"
    if so.exists():
        return so, 0.0, True
    return so, _compile(cc, sources, so, include=build.include_flags(gdir),
                        flags=KERNEL_CFLAGS), False


_COPIES: list[str] = []


def _remove_copies() -> None:
    for d in _COPIES:
        shutil.rmtree(d, ignore_errors=True)


atexit.register(_remove_copies)


def _kernels_function(rod: ReleasedRod, so: Path,
                      error_control: str = "state") -> tuple[ca.Function, Any]:
    """casadi.external over a private copy of the kernels library, set up for this rod
    (with its relaxation terms, if any)."""
    m = rod.model
    di = rod.di
    s = _scales(rod, "ode", error_control)
    pat = m.sparsity()[di][:, di].tocsc()
    pat.sort_indices()
    rows = pat.indices.astype(np.int64)
    cols = np.repeat(np.arange(di.size), np.diff(pat.indptr)).astype(np.int64)
    i, j = di[rows], di[cols]
    src = (m.kl + m.ku + i - j) + j * m.ldab
    coef = -s[cols] / (rod.D[i] * s[rows])
    nx = di.size
    sp = np.concatenate([[nx, 1, 1], [nx, 1, 0, 0], [nx, 0, 1], [0, nx, 1],
                         [nx, nx], pat.indptr, pat.indices]).astype(np.int64)
    a = m.arrays
    keep = {"par": a.par.copy(), "seg": a.seg.copy(), "jnt": a.jnt.copy(),
            "nload": a.nload.copy(), "sload": a.sload.copy(),
            "di": di.astype(np.int32), "s": np.ascontiguousarray(s),
            "fac": np.ascontiguousarray(-1.0 / (rod.D[di] * s)),
            "yfix": rod.y0.copy(), "src": np.ascontiguousarray(src, dtype=np.int64),
            "coef": np.ascontiguousarray(coef), "sp": sp,
            "theta": np.ascontiguousarray(a.theta, dtype=float),
            "segb": np.ascontiguousarray(a.segb, dtype=float),
            "jntb": np.ascontiguousarray(a.jntb, dtype=float)}
    tmp = tempfile.mkdtemp(prefix="kvrod_idas_kernels_")
    _COPIES.append(tmp)
    path = Path(tmp) / so.name
    shutil.copyfile(so, path)
    lib = ctypes.CDLL(str(path))
    P = ctypes.c_void_p
    lib.kv_setup.argtypes = [ctypes.c_int, P, P, P, P, P, ctypes.c_int, ctypes.c_int,
                             ctypes.c_int, P, P, P, P, ctypes.c_longlong, P, P, P,
                             ctypes.c_int, P, P, P]
    lib.kv_setup.restype = ctypes.c_int
    if (lib.kvrod_kl(m.N, a.branches), lib.kvrod_ku(m.N, a.branches)) != (m.kl, m.ku):
        raise RuntimeError(f"the kernels library's band ({lib.kvrod_kl(m.N, a.branches)}, "
                           f"{lib.kvrod_ku(m.N, a.branches)}) is not the model's "
                           f"({m.kl}, {m.ku})")
    k = keep
    rc = lib.kv_setup(m.N, *(k[x].ctypes.data for x in ("par", "seg", "jnt", "nload",
                                                         "sload")),
                      m.n, nx, m.ldab, k["di"].ctypes.data, k["s"].ctypes.data,
                      k["fac"].ctypes.data, k["yfix"].ctypes.data, int(src.size),
                      k["src"].ctypes.data, k["coef"].ctypes.data, k["sp"].ctypes.data,
                      a.branches, *(k[x].ctypes.data for x in ("theta", "segb", "jntb")))
    if rc:
        raise RuntimeError("kv_setup failed: " + ("out of memory" if rc == 1 else
                                                  f"band storage ldab = {m.ldab} too small"))
    keep["lib"] = lib
    return ca.external("rod_ode", str(path)), keep


def build_function(rod: ReleasedRod, form: str = "ode", build_kind: str = "flat",
                   cache_dir: Path | None = None, error_control: str = "state") -> Opponent:
    """The rod as CasADi's DAE function (see the module docstring).

    build_kind: "flat" (SX, generated with its Jacobian into one C file, gcc, cached),
    "kernels" (ODE form only: kvrod's own compiled residual and banded Jacobian behind
    CasADi's external-function API, ``bench/idas_kernels.c``), "map" (the MX function
    over the kernel maps, generated and compiled like "flat"), "sx" (SX virtual machine),
    "mx" (MX virtual machine).
    error_control: the ODE form's scaling (:func:`_scales`): "state" (kvrod's default
    atol per unit rtol) or "configuration" (the velocities' scales times OUT_OF_TEST, so
    that CVODES's scalar abstol leaves them out of its error test; IDAS does not need it:
    :func:`integrate` gives it per-component tolerances).
    """
    if form not in FORMS:
        raise ValueError(f"form = {form!r} is outside the allowed range: {FORMS}")
    if build_kind not in BUILDS:
        raise ValueError(f"build = {build_kind!r} is outside the allowed range: {BUILDS}")
    if error_control not in ERROR_CONTROLS:
        raise ValueError(f"error_control = {error_control!r} is outside the allowed range: "
                         f"{ERROR_CONTROLS}")
    if form != "ode" and error_control != "state":
        raise ValueError("the velocities scaled out of the error test: ODE form only")
    name = f"rod_{form}"
    di, ai = rod.di, rod.ai
    xs = di
    s = _scales(rod, form, error_control)
    zs = ai if form == "dae" else np.zeros(0, dtype=int)
    seconds: dict[str, float] = {}
    ec = error_control
    if build_kind == "kernels":
        if form != "ode":
            raise ValueError("the kernels build has the ODE form only")
        so, sec, cached = kernels_library(cache_dir)
        seconds["compile"] = sec
        t0 = time.perf_counter()
        fn, keep = _kernels_function(rod, so, error_control)
        seconds["load"] = time.perf_counter() - t0
        return Opponent(fn, form, build_kind, xs, s, zs, seconds, cached=cached,
                        library=str(so), keep=keep, error_control=ec)
    compiled = build_kind in ("flat", "map")
    if compiled:
        cc = native.find_compiler()
        if cc is None:
            raise RuntimeError("no C compiler for the compiled IDAS opponent")
        key = _cache_key(rod, form, build_kind, cc, error_control)
        cdir = _cache_dir(cache_dir)
        so = cdir / f"{name}_{build_kind}_N{rod.N}_{key}.so"
        if so.exists():
            t0 = time.perf_counter()
            fn = ca.external(name, str(so))
            seconds["load"] = time.perf_counter() - t0
            return Opponent(fn, form, build_kind, xs, s, zs, seconds, cached=True,
                            library=str(so), error_control=ec)
    t0 = time.perf_counter()
    sym = ca.SX if build_kind in ("flat", "sx") else ca.MX
    t, x, z, ode, alg, xs, s, zs = _symbolic(rod, form, sym, error_control)
    p, u = sym.sym("p", 0), sym.sym("u", 0)
    fn = ca.Function(name, [t, x, z, p, u], [ode, alg, sym(0, 1), sym(0, 1)],
                     ca.dyn_in(), ca.dyn_out())
    seconds["build"] = time.perf_counter() - t0
    if not compiled:
        return Opponent(fn, form, build_kind, xs, s, zs, seconds, error_control=ec)
    cdir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=cdir, prefix="codegen_") as tmp:
        t0 = time.perf_counter()
        cg = ca.CodeGenerator(f"{name}.c")
        cg.add(fn)
        cg.add(fn.jacobian())    # exported as jac_<name>: casadi.external uses it
        cg.generate(tmp + "/")
        src = Path(tmp) / f"{name}.c"
        c_bytes = src.stat().st_size
        seconds["codegen"] = time.perf_counter() - t0
        seconds["compile"] = _compile(cc, [src], so)
    t0 = time.perf_counter()
    fn = ca.external(name, str(so))
    seconds["load"] = time.perf_counter() - t0
    return Opponent(fn, form, build_kind, xs, s, zs, seconds, c_bytes=c_bytes,
                    library=str(so), error_control=ec)


# --------------------------------------------------------------------------------------
# Integration
# --------------------------------------------------------------------------------------


@dataclass
class Run:
    """One integration: wall time (the integrator call only), SUNDIALS counters, the tip's
    x and x' on the output grid, and the solver's set-up time."""

    solver: str
    label: str
    rtol: float
    ok: bool
    wall: float = math.nan
    setup: float = math.nan
    stats: dict[str, int] = field(default_factory=dict)
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tip_x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    tip_vx: np.ndarray = field(default_factory=lambda: np.zeros(0))
    message: str = ""
    walls: list[float] = field(default_factory=list)
    states: np.ndarray | None = None    # (n, len(t)) with ``keep_states``

    @property
    def steps(self) -> int:
        return int(self.stats.get("nsteps", 0))

    @property
    def us_per_step(self) -> float:
        return 1e6 * self.wall / self.steps if self.ok and self.steps else math.nan


def integrate(rod: ReleasedRod, opp: Opponent, t_end: float, output_step: float,
              rtol: float, atol: np.ndarray | float | None = None, solver: str = "idas",
              linear_solver: str = "csparse", repeat: int = 1,
              extra: dict | None = None, grid: np.ndarray | None = None,
              keep_states: bool = False, error_control: str | None = None,
              max_order: int | None = None) -> Run:
    """Integrate the released rod with IDAS or CVODES over [0, t_end], output every
    ``output_step`` (or on ``grid``, which starts at 0).

    atol: None (kvrod's per-component ``default_atol`` at this rtol), an array (n,) or a
    scalar (m, m/s, 1, rad/s alike). IDAS gets per-component values through ``abstolv``
    (divided by the ODE form's scaling). CVODES takes only a scalar ``abstol``: it gets
    rtol on the ODE form's scaled state, i.e. rtol * scale per component, which is
    kvrod's default atol for rtol >= 1e-8 (below, default_atol's round-off floors differ);
    other atol values are refused for CVODES.
    error_control: "state" (every component in the error test) or "configuration" (the
    velocities out of it: their atol times OUT_OF_TEST, weights ~1e-12 of the others',
    kvrod's error mask; CVODES needs an opponent built with that scaling); default: the
    opponent's.
    max_order: the highest BDF order (default 5): CasADi's ``max_multistep_order`` and
    ``max_order``; CasADi 3.8's CVODES ignores the first (same steps for 1..5) and obeys
    the second, its IDAS obeys either.
    ``repeat``: integrate that many times and keep the median wall time.
    """
    if solver not in ("idas", "cvodes"):
        raise ValueError(f"solver = {solver!r} is outside the allowed range: idas, cvodes")
    if solver == "cvodes" and opp.form != "ode":
        raise ValueError("CVODES needs the ODE form")
    ec = opp.error_control if error_control is None else error_control
    if ec not in ERROR_CONTROLS:
        raise ValueError(f"error_control = {ec!r} is outside the allowed range: "
                         f"{ERROR_CONTROLS}")
    if solver == "cvodes" and ec != opp.error_control:
        raise ValueError(f"CVODES controls what the opponent's scaling says "
                         f"({opp.error_control!r}): build it with error_control={ec!r}")
    if max_order is not None and not 1 <= max_order <= 5:
        raise ValueError(f"max_order = {max_order} is outside the allowed range: 1..5")
    if grid is None:
        grid = np.linspace(0.0, t_end, int(round(t_end / output_step)) + 1)
    if atol is None:
        atol_y = rod.atol(rtol)
    else:
        atol_y = np.broadcast_to(np.asarray(atol, dtype=float), (rod.n,))
    if ec == "configuration":
        atol_y = np.array(atol_y)
        atol_y[rod.velocity_mask] *= OUT_OF_TEST
    idx = np.concatenate([opp.xs, opp.zs])
    scale = np.concatenate([opp.s, np.ones(opp.zs.size)])
    atol_v = atol_y[idx] / scale
    opts: dict[str, Any] = {"reltol": rtol, "linear_solver": linear_solver,
                            "max_num_steps": 10**8, "disable_internal_warnings": True}
    if solver == "idas":
        opts.update(abstolv=atol_v.tolist(), calc_ic=False,
                    init_xdot=(rod.yp0[opp.xs] / opp.s).tolist())
    elif atol is None:
        opts["abstol"] = rtol
    else:
        raise ValueError("CVODES takes per-component tolerances only through the ODE "
                         "form's scaling: atol must be None")
    if max_order is not None:
        opts.update(max_multistep_order=int(max_order), max_order=float(max_order))
    opts.update(extra or {})
    label = f"{solver} ({opp.label}, {linear_solver})"
    if ec != "state" and solver == "idas":
        label = label[:-1] + ", velocities out of the error test)"
    if max_order is not None:
        label = label[:-1] + f", max order {max_order})"
    t0 = time.perf_counter()
    integ = ca.integrator("I", solver, opp.fn, 0.0, grid[1:].tolist(), opts)
    setup = time.perf_counter() - t0
    x0 = rod.y0[opp.xs] / opp.s
    z0 = rod.y0[opp.zs]
    walls = []
    try:
        for _ in range(max(1, repeat)):
            t0 = time.perf_counter()
            r = integ(x0=x0, z0=z0) if opp.zs.size else integ(x0=x0)
            walls.append(time.perf_counter() - t0)
    except RuntimeError as exc:
        return Run(solver, label, rtol, False, message=str(exc)[-300:], setup=setup)
    st = integ.stats()
    stats = {k: int(st[k]) for k in ("nsteps", "nfevals", "nlinsetups", "netfails",
                                     "nniters", "nncfails") if k in st}
    xf = np.asarray(r["xf"])
    kx = int(np.nonzero(opp.xs == rod.tip_x)[0][0])
    kv = int(np.nonzero(opp.xs == rod.tip_vx)[0][0])
    tip_x = np.concatenate([[rod.y0[rod.tip_x]], xf[kx] * opp.s[kx]])
    tip_vx = np.concatenate([[rod.y0[rod.tip_vx]], xf[kv] * opp.s[kv]])
    states = None
    if keep_states:
        states = np.repeat(rod.y0[:, None], grid.size, axis=1)
        states[opp.xs, 1:] = xf * opp.s[:, None]
        if opp.zs.size:
            states[opp.zs, 1:] = np.asarray(r["zf"])
    return Run(solver, label, rtol, True, float(np.median(walls)), setup, stats, grid,
               tip_x, tip_vx, walls=walls, states=states)


def tip_maxima(t: np.ndarray, x: np.ndarray, v: np.ndarray, offset: float = 0.0,
               initial: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Maxima of x(t) (minus ``offset``) from samples of x and x': where x' changes sign
    from + to -, the zero of the derivative of the cubic Hermite interpolant; a release at
    rest with positive x counts as a maximum at t[0] (as ``kvrod simulate``)."""
    ts, xs = [], []
    if initial and x[0] - offset > 0:
        ts.append(float(t[0]))
        xs.append(float(x[0] - offset))
    for k in np.nonzero((v[:-1] > 0) & (v[1:] <= 0))[0]:
        h = t[k + 1] - t[k]
        x0, x1, m0, m1 = x[k], x[k + 1], v[k] * h, v[k + 1] * h
        # p(s) = (2s^3-3s^2+1)x0 + (s^3-2s^2+s)m0 + (-2s^3+3s^2)x1 + (s^3-s^2)m1
        a = 6 * x0 + 3 * m0 - 6 * x1 + 3 * m1      # p'(s) = a s^2 + b s + c
        b = -6 * x0 - 4 * m0 + 6 * x1 - 2 * m1
        c = m0
        roots = np.roots([a, b, c]) if abs(a) > 1e-300 else np.array([-c / b])
        roots = roots[np.isreal(roots)].real
        roots = roots[(roots >= -1e-12) & (roots <= 1 + 1e-12)]
        sr = float(roots[0]) if roots.size else (0.0 if x0 >= x1 else 1.0)
        p = ((2 * sr**3 - 3 * sr**2 + 1) * x0 + (sr**3 - 2 * sr**2 + sr) * m0
             + (-2 * sr**3 + 3 * sr**2) * x1 + (sr**3 - sr**2) * m1)
        if p - offset > 0:
            ts.append(float(t[k] + sr * h))
            xs.append(float(p - offset))
    return np.array(ts), np.array(xs)


# --------------------------------------------------------------------------------------
# The command
# --------------------------------------------------------------------------------------


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m bench.idas_script",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--problem", default="cantilever",
                    help="a built-in problem name or a TOML file, released from its static "
                         "deflection (default: cantilever); e.g. "
                         "examples/maxwell_cantilever.toml")
    ap.add_argument("--n-elements", type=int, default=None,
                    help="default: the problem's (50 for the cantilever)")
    ap.add_argument("--t-end", type=float, default=None,
                    help="s (default: the problem's, 10 for the cantilever)")
    ap.add_argument("--rtol", type=float, default=1e-6)
    ap.add_argument("--atol", type=float, default=None,
                    help="scalar absolute tolerance (default: kvrod's per-component "
                         "default_atol)")
    ap.add_argument("--output-step", type=float, default=None,
                    help="s (default: the problem's, 0.005)")
    ap.add_argument("--solver", choices=("idas", "cvodes"), default="idas")
    ap.add_argument("--form", choices=FORMS, default="ode")
    ap.add_argument("--build", choices=BUILDS, default="flat")
    ap.add_argument("--error-control", choices=("auto", *ERROR_CONTROLS), default="auto",
                    help="what the error test controls: state (every component), "
                         "configuration (velocities out: their atol times 2^40, as kvrod's "
                         "error mask) or auto (default: kvrod's default for the problem, "
                         "configuration for a generalized Maxwell rod, else state)")
    ap.add_argument("--max-order", type=int, default=None, choices=range(1, 6),
                    metavar="{1..5}", help="highest BDF order (default 5)")
    ap.add_argument("--json", action="store_true", help="print one JSON line instead")
    args = ap.parse_args(argv)
    if args.n_elements is not None and args.n_elements < 1:
        ap.error(f"--n-elements = {args.n_elements} is outside the allowed range: >= 1")
    if not ((args.t_end is None or args.t_end > 0) and args.rtol > 0):
        ap.error("--t-end and --rtol must be > 0")
    wall0 = time.perf_counter()
    try:
        rod = released_rod(args.n_elements, args.t_end, args.rtol, problem=args.problem)
    except (ProblemFileError, ParameterError) as exc:
        ap.error(f"--problem {args.problem}: {exc}")
    except RuntimeError as exc:      # not in the ODE form's reach (released_rod's checks)
        ap.error(f"--problem {args.problem}: {exc}")
    t_rod = time.perf_counter() - wall0
    t_end = rod.problem.simulation.t_end
    ec = (rod.default_error_control() if args.error_control == "auto"
          else args.error_control)
    t0 = time.perf_counter()
    if args.solver == "cvodes" and ec != "state" and args.form != "ode":
        ap.error("--error-control configuration with CVODES needs --form ode")
    opp = build_function(rod, args.form, args.build,
                         error_control=ec if args.solver == "cvodes" else "state")
    t_build = time.perf_counter() - t0
    dt = args.output_step or rod.problem.simulation.output_step
    run = integrate(rod, opp, t_end, dt, args.rtol, args.atol, args.solver,
                    error_control=ec, max_order=args.max_order)
    if not run.ok:
        print(f"{run.label} failed: {run.message}", file=sys.stderr)
        return 1
    offset = float(rod.model.reference[rod.tip_x])
    pt, px = tip_maxima(run.t, run.tip_x, run.tip_vx, offset)
    out = {"solver": run.label, "N": rod.N, "n": rod.n, "t_end": t_end,
           "rtol": args.rtol, "atol": "default_atol" if args.atol is None else args.atol,
           "integration_s": run.wall, "setup_s": run.setup, "steps": run.steps,
           "us_per_step": run.us_per_step, **run.stats,
           "rod_and_statics_s": t_rod, "build_s": t_build, "library_cached": opp.cached,
           "peaks_t": pt.tolist(), "peaks_x": px.tolist(),
           "process_s_so_far": time.perf_counter() - wall0}
    if args.problem != "cantilever":       # (the cantilever's output as it always was)
        out.update(problem=rod.problem.name, error_control=ec)
    if args.json:
        print(json.dumps(out))
        return 0
    what = "" if args.problem == "cantilever" else f"{rod.problem.name}, "
    print(f"{run.label}: {what}N = {rod.N} (n = {rod.n}), {t_end:g} s, rtol {args.rtol:g}, "
          f"atol {out['atol']}")
    print(f"integration {run.wall:.3f} s, {run.steps} steps ({run.us_per_step:.1f} us/step), "
          f"{run.stats.get('nlinsetups', 0)} Jacobian+LU; set-up {run.setup:.3f} s; rod and "
          f"statics {t_rod:.3f} s; functions {t_build:.3f} s "
          f"({'cached library' if opp.cached else 'built'})")
    print("tip maxima (t s, x m):")
    for a, b in zip(pt, px, strict=True):
        print(f"  {a:.6f} {b:.8f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
