"""PyElastica (``pyelastica``, explicit position Verlet) on the same cantilever.

PyElastica's rods are circular: we build one with the same area (so the same mass) and
then override the shear/stretch matrix, the bend/twist matrix and the mass second moments
with kvrod's square-section values (the model's arrays of the paper's cantilever,
``build_model(load_problem("cantilever"))``: kappa G A, E A, E I, G J_T, rho I). Its
clamp (``OneEndFixedBC``: node 0 and the first element's directors) sits effectively at
h/2, so its frequencies carry an O(h) error that kvrod's half-cell clamp avoids.

Protocol per N (25, 50, 100):

1. static: the tip force (0.05 N along e1) on, PyElastica's ``AnalyticalLinearDamper``
   with ``uniform_damping_constant`` 7 1/s (about critical for the first mode) for 6 s;
   static tip error against the Simo-Reissner shooting solution
   (``references/reissner.py``) with the same stiffnesses; kvrod's
   ``static_equilibrium`` error beside it.
2. largest stable step: position Verlet on the release (force off) at
   dt = dt0 * 1.25^k for growing k, each for 2 s; the last dt that stays finite and bounded
   (every node within 1.2 L of the origin) is kept, and reduced by 1.25 until the full
   10 s run stays bounded.
3. release, 10 s, undamped and with its own damper at nu = omega_1^2 tau_E (the velocity
   damping rate that gives the first mode kvrod's Kelvin-Voigt damping ratio
   zeta_1 = omega_1 tau_E / 2; higher modes are then damped at the same rate nu rather
   than proportionally to omega^2): wall time, steps, period of tip x (mean spacing of
   upward zero crossings) against kvrod's.

PyElastica has no strain-rate (Kelvin-Voigt) damping: its dampers act on absolute
velocities. An explicit method with Kelvin-Voigt damping is bounded by the fastest decay
rate of the linearised rod: :func:`explicit_step_estimate` computes the eigenvalues of
``-D^-1 dg/dy`` (F = D y' + g(y)) at the straight state with ``RodModel.dF_dy_sparse``
and reports dt ~ 2/|lambda|_max and the steps that 10 s would need.
"""

from __future__ import annotations

import math
import time

import numpy as np

from bench import integrators as bi
from runtime.problem.assemble import build_model
from runtime.problem.registry import load_problem

SIZES = (25, 50, 100)


def _paper() -> tuple[dict, tuple[float, float, float]]:
    """The cantilever's numbers (examples/cantilever.toml) and its tip force (N)."""
    p = load_problem("cantilever")
    sec = dict(p.section.dims)
    par = {"length": p.rod.length, "density": p.material.density,
           "youngs_modulus": p.material.youngs_modulus,
           "poisson_ratio": p.material.poisson_ratio, "tau_B": p.material.tau_B,
           "width": sec["width"], "height": sec["height"]}
    force = next(ld.vector for ld in p.loads if ld.kind == "force")
    return par, tuple(float(v) for v in force)


PAPER, TIP_FORCE = _paper()


def matrices(N: int) -> dict[str, np.ndarray]:
    """kvrod's section values of the paper's cantilever: C_F (3,) = (GA1, GA2, EA), C_M
    (3,) = (EI1, EI2, GJ_T), rhoA (1,), rhoI (3,) (uniform rod: element 0)."""
    a = build_model(load_problem("cantilever", {"n_elements": N})).arrays
    return {"C_F": a.seg_field("C_F")[0].copy(), "C_M": a.jnt_field("C_M")[1].copy(),
            "rhoA": a.seg_field("rhoA")[0].copy(), "rhoI": a.seg_field("rhoI")[0].copy()}


def available() -> str | None:
    """PyElastica's version, or None if it cannot be imported."""
    try:
        import elastica
    except Exception:  # noqa: BLE001 - any import failure means "not available"
        return None
    return str(getattr(elastica, "__version__", None) or _dist_version())


def _dist_version() -> str:
    from importlib.metadata import version

    return version("pyelastica")


def reissner_tip(N: int = 50) -> tuple[float, float]:
    """(x, z) of the Simo-Reissner tip under the paper's load (same stiffnesses as kvrod)."""
    from references.reissner import solve_reissner

    mats = matrices(N)
    sol = solve_reissner(TIP_FORCE[0], L=PAPER["length"], EA=float(mats["C_F"][2]),
                         GA=float(mats["C_F"][0]), EI=float(mats["C_M"][0]))
    return float(sol.tip[0]), float(sol.tip[1])


def _simulation(N: int, force_until: float, damping: list[tuple[float, float, float]],
                dt: float):
    """A PyElastica simulation; force on for t < force_until; damping = (t0, t1, nu)."""
    import elastica as ea

    class Sim(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.Damping):
        pass

    class TipForce(ea.NoForces):
        def __init__(self, force: np.ndarray, until: float) -> None:
            super().__init__()
            self.force, self.until = force, until

        def apply_forces(self, system, time: float = 0.0) -> None:
            if time < self.until:
                ramp = min(1.0, time / 1.0) if self.until > 1.0 else 1.0
                system.external_forces[:, -1] += ramp * self.force

    class WindowDamper(ea.DamperBase):
        """Exact exponential velocity damping exp(-nu dt) for t0 <= t < t1 (like
        AnalyticalLinearDamper's uniform protocol, switchable in time)."""

        def __init__(self, windows, time_step: float, **kwargs) -> None:
            super().__init__(**kwargs)
            self.windows, self.dt = windows, time_step

        def dampen_rates(self, system, time) -> None:
            for t0, t1, nu in self.windows:
                if t0 <= time < t1:
                    f = math.exp(-nu * self.dt)
                    system.velocity_collection[:] *= f
                    system.omega_collection[:] *= f

    mats = matrices(N)
    L, A = PAPER["length"], PAPER["width"] * PAPER["height"]
    sim = Sim()
    rod = ea.CosseratRod.straight_rod(
        N, np.zeros(3), np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), L,
        math.sqrt(A / math.pi), PAPER["density"], youngs_modulus=PAPER["youngs_modulus"],
        shear_modulus=PAPER["youngs_modulus"] / (2 * (1 + PAPER["poisson_ratio"])))
    dl = L / N
    for i in range(N):
        rod.shear_matrix[..., i] = np.diag(mats["C_F"])
        rod.mass_second_moment_of_inertia[..., i] = np.diag(mats["rhoI"] * dl)
        rod.inv_mass_second_moment_of_inertia[..., i] = np.diag(1.0 / (mats["rhoI"] * dl))
    for i in range(N - 1):
        rod.bend_matrix[..., i] = np.diag(mats["C_M"])
    sim.append(rod)
    sim.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,),
                             constrained_director_idx=(0,))
    sim.add_forcing_to(rod).using(TipForce, force=np.array(TIP_FORCE), until=force_until)
    if damping:
        sim.dampen(rod).using(WindowDamper, windows=damping, time_step=dt)
    sim.finalize()
    return sim, rod, ea.PositionVerlet()


def _run(sim, rod, stepper, t0: float, t1: float, dt: float, record: float = 0.01):
    """Step from t0 to t1; returns (ok, wall, steps, times, tip x)."""
    n = int(round((t1 - t0) / dt))
    every = max(1, int(round(record / dt)))
    ts, xs = [], []
    limit = float(np.sum(rod.rest_lengths))  # no node can leave the ball of radius L
    t = np.float64(t0)
    pos = rod.position_collection
    w0 = time.perf_counter()
    for k in range(n):
        t = stepper.step(sim, t, np.float64(dt))
        if k % every == 0:
            x = float(pos[0, -1])
            if not (math.isfinite(x) and abs(x) < 1.2 * limit):
                return False, time.perf_counter() - w0, k + 1, np.array(ts), np.array(xs)
            ts.append(float(t))
            xs.append(x)
    wall = time.perf_counter() - w0
    ok = bool(np.all(np.isfinite(pos)) and np.max(np.abs(pos)) < 1.2 * limit)
    return ok, wall, n, np.array(ts), np.array(xs)


def period(ts: np.ndarray, xs: np.ndarray) -> float | None:
    """Mean spacing of upward zero crossings of x(t) (linear interpolation)."""
    i = np.nonzero((xs[:-1] < 0) & (xs[1:] >= 0))[0]
    if i.size < 2:
        return None
    tc = ts[i] - xs[i] * (ts[i + 1] - ts[i]) / (xs[i + 1] - xs[i])
    return float(np.mean(np.diff(tc)))


def kvrod_period(N: int, T: float = 10.0) -> float | None:
    from runtime.solvers.integrator import solve

    c = bi.rod(N, T)
    grid = np.linspace(0.0, T, 2001)
    s = solve(c.model, (0.0, T), c.y0, c.yp0, rtol=1e-7, atol=c.atol(1e-7), t_eval=grid)
    return period(grid, s.y[c.tip_x])


def elastica_case(N: int, T: float = 10.0, t_static: float = 6.0, log=print) -> dict:
    ref = reissner_tip(N)
    mats = matrices(N)
    omega1 = 1.875104**2 * math.sqrt(float(mats["C_M"][0]) / (float(mats["rhoA"][0])
                                                           * PAPER["length"] ** 4))
    nu_kv = omega1**2 * PAPER["tau_B"]
    out: dict = {"N": N, "reissner_tip": ref, "nu_damper": nu_kv}
    # 1. static, with a small step (stable for any reasonable N here)
    dt_s = 0.25 * (PAPER["length"] / N) / math.sqrt(PAPER["youngs_modulus"]
                                                    / PAPER["density"])
    w0 = time.perf_counter()
    sim, rod, st = _simulation(N, t_static, [(0.0, t_static, 7.0)], dt_s)
    out["setup_seconds"] = time.perf_counter() - w0
    ok, wall, n, _, _ = _run(sim, rod, st, 0.0, t_static, dt_s)
    tip = rod.position_collection[:, -1].copy()
    out["static"] = {"ok": ok, "dt": dt_s, "steps": n, "wall": wall,
                     "tip": tip.tolist(),
                     "tip_error": float(math.hypot(tip[0] - ref[0], tip[2] - ref[1]))}
    c = bi.rod(N, T)
    ty = c.model.tip_position(c.static_y)
    out["kvrod_static_tip_error"] = float(math.hypot(ty[0] - ref[0], ty[2] - ref[1]))
    state = (rod.position_collection.copy(), rod.director_collection.copy())

    def released(dt: float, nu: float | None):
        damping = [(0.0, math.inf, nu)] if nu else []
        sim, rod, st = _simulation(N, -1.0, damping, dt)
        rod.position_collection[:] = state[0]
        rod.director_collection[:] = state[1]
        return sim, rod, st

    # 2. largest stable step (undamped), 2 s probes
    dt, best = dt_s, dt_s
    while True:
        sim, rod, st = released(dt, None)
        ok, *_ = _run(sim, rod, st, 0.0, 2.0, dt)
        if not ok:
            break
        best = dt
        dt *= 1.25
        if dt > 1e-2:
            break
    out["dt_stable"] = best
    # 3. release runs at that step
    for label, nu in (("undamped", None), ("damped", nu_kv)):
        dt = best
        for _ in range(8):
            sim, rod, st = released(dt, nu)
            ok, wall, n, ts, xs = _run(sim, rod, st, 0.0, T, dt)
            if ok:
                break
            dt /= 1.25
        out[label] = {"ok": ok, "dt": dt, "steps": n, "wall": wall,
                      "period": period(ts, xs) if ok else None,
                      "tip_x_at_end": float(xs[-1]) if ok and xs.size else None}
        log(f"  PyElastica N={N} {label}: dt {dt:.2e}, {n} steps, {wall:.2f} s, "
            f"period {out[label]['period']}")
    out["kvrod_period"] = kvrod_period(N, T)
    return out


def explicit_step_estimate(N: int) -> dict:
    """Fastest decay/oscillation rate of the linearised Kelvin-Voigt rod at the straight
    state and the explicit step it allows (dt ~ 2/|lambda|_max)."""
    m = build_model(load_problem("cantilever", {"n_elements": N}))
    m.at(0.0)                 # released: no load
    y = m.initial_state()
    z = np.zeros(m.n)
    di = np.nonzero(m.differential)[0]
    J = m.dF_dy_sparse(0.0, y, z).toarray()[np.ix_(di, di)]
    D = m.dF_dyp_sparse(0.0, y, z).diagonal()[di]
    lam = np.linalg.eigvals(-J / D[:, None])
    k = int(np.argmax(np.abs(lam)))
    lam_max = abs(lam[k])
    osc = lam[np.abs(lam.imag) > 1e-9 * lam_max]
    dt = 2.0 / lam_max
    return {"N": N, "lambda_max_abs": float(lam_max), "lambda_at_max": [float(lam[k].real),
                                                                      float(lam[k].imag)],
            "min_real": float(lam.real.min()),
            "oscillatory_modes": int(osc.size // 2),
            "dt_explicit": dt, "steps_for_10s": 10.0 / dt}


def run(sizes=SIZES, T: float = 10.0, log=print) -> dict:
    version = available()
    out: dict = {"pyelastica": version, "estimates": []}
    for N in (50, 100):
        e = explicit_step_estimate(N)
        out["estimates"].append(e)
        log(f"  Kelvin-Voigt explicit step N={N}: |lambda|max {e['lambda_max_abs']:.2e} 1/s, "
            f"dt ~ {e['dt_explicit']:.1e} s, {e['steps_for_10s']:.1e} steps for 10 s")
    if version is None:
        out["skipped"] = ("pyelastica is not installed (pip install 'pyelastica==1.0.0'); "
                          "the PyElastica runs were skipped")
        log("  " + out["skipped"])
        return out
    w0 = time.perf_counter()
    sim, rod, st = _simulation(4, 1.0, [(0.0, 1.0, 1.0)], 1e-4)  # numba compilation
    _run(sim, rod, st, 0.0, 1e-3, 1e-4)
    out["warmup_seconds"] = time.perf_counter() - w0
    out["cases"] = [elastica_case(N, T, log=log) for N in sizes]
    return out
