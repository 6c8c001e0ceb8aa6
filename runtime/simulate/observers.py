"""The rod run's observers (the hooks they implement: :class:`runtime.solvers.driver.Observer`):
the energy audit's running integrals (:class:`EnergyIntegrator`), output samples of the
ends, energies and reactions (:class:`Sampler`), maxima of one coordinate
(:class:`Maxima`), full states for ParaView (:class:`Snapshots`), the deformed centreline
(:class:`Centreline`), progress (:class:`Progress`).

They are called in the order given, so an observer may use the results of earlier ones
(:class:`Sampler` reads the running integrals of :class:`EnergyIntegrator`). All of them
are ``sparse``: with the compiled step loop (``runtime/solvers/native/step_loop.c``) the
energy audit and the output samples run inside it (``attach``), so do the centreline
frames where the loop's frame grid is free (``into_core``), the snapshots (and frames
that cannot go into the loop) are taken on copies of the steps that reach their times,
handed over in batches (``replay_times``), and maxima stop the loop where the velocity
changes sign
(``watches``); ``step`` of a sparse observer may be called for any step, not only those it
asked for.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from runtime.solvers.driver import RunState
from runtime.solvers.native.step_loop import AUDIT_NODES
from runtime.solvers.roots import bracketed_root


class EnergyModel(Protocol):
    """The part of a model the energy observers need."""

    def energy_scalars(self, t: float, y: np.ndarray, yp: np.ndarray | None = None
                       ) -> tuple[float, ...]:
        """(T, W, 2D, P_ext[, P_bc]) of a state: J, J, W, W[, W]."""
        ...

    def energies(self, ts: np.ndarray, ys: np.ndarray, yps: np.ndarray) -> np.ndarray:
        """The same for m states at once: (m, 5)."""
        ...


def audit_polynomial(ht: list[float], hg: list[tuple[float, float]], t0: float, h: float
                     ) -> list[list[float]]:
    """The polynomials through the audit's nodes ``(ht[j], hg[j])`` (times, (2D, P); the
    last two: the step's start and end) in x = (t - t0) / h: for 2D and for P, the
    monomial coefficients ``[c_0, ..., c_3]`` (Newton's divided differences expanded by
    Horner's scheme), for 2D the straight line through the step's ends where the cubic's
    mean over the step is negative (float for float the arithmetic of
    ``kv_audit_polynomial`` in native/step_loop.c, so that both paths give the same
    audit)."""
    m = len(ht)
    x = [(tj - t0) / h for tj in ht]
    out = []
    for c in range(2):
        d = [g[c] for g in hg]
        for k in range(1, m):
            for j in range(m - 1, k - 1, -1):
                d[j] = (d[j] - d[j - 1]) / (x[j] - x[j - k])
        p = [0.0] * AUDIT_NODES
        p[0] = d[m - 1]
        for k in range(m - 2, -1, -1):
            for r in range(m - 1 - k, 0, -1):
                p[r] = p[r - 1] - x[k] * p[r]
            p[0] = d[k] - x[k] * p[0]
        if c == 0 and m > 2 and audit_integral(m, p, 1.0) < 0.0:
            # 2D >= 0: an edge the cubic overshoots (a contact's release) gets the
            # straight line through the step's two ends
            g0, g1 = hg[m - 2][0], hg[m - 1][0]
            p = [0.0] * AUDIT_NODES
            p[0], p[1] = g0, g1 - g0
        out.append(p)
    return out


def audit_integral(m: int, p: list[float], x: float) -> float:
    """The integral over [0, x] of ``p[0] + p[1] x + ...`` (its first ``m`` coefficients;
    ``kv_audit_integral``)."""
    s = 0.0
    for r in range(m - 1, -1, -1):
        s = s * x + p[r] / float(r + 1)
    return s * x


class EnergyIntegrator:
    """Running integrals of the dissipated power 2D and the external power P over the run.

    2D and P are evaluated once per accepted step, at its end on its interpolant (at the
    run's start and after every restart also at the step's start), and each step is
    integrated on the cubic through the last ``AUDIT_NODES`` = 4 of these nodes: a
    variable-step Adams-Moulton rule of order 4 (lower right after a (re)start, where
    fewer nodes exist; they begin again there because P may jump). ``partial`` gives the
    integrals from the step's start to a ``t`` inside it (for outputs) on the same
    polynomial, so outputs and the running totals agree at step ends. Why not Gauss
    nodes inside each step: three evaluations a step were 30 % of ``simulate``'s compiled
    loop, and the audit is no more exact for them (both agree to well inside the
    integrator's tolerance: tests/runtime/test_energy_audit.py). ``dissipated`` and
    ``external_work`` hold the integrals up to the last accepted step (J). The external
    power includes the power of prescribed end motion when the model reports it (a fifth
    scalar). With the compiled step loop the same arithmetic runs in C
    (``audit_step`` in native/step_loop.c).
    """

    name = "energy"
    sparse = True

    def __init__(self, model: EnergyModel) -> None:
        self.model = model
        self.dissipated = 0.0
        self.external_work = 0.0
        self._key: tuple[float, float] | None = None
        self._ht: list[float] = []                   # the nodes' times
        self._hg: list[tuple[float, float]] = []     # (2D, P) at them
        self._coef: list[list[float]] = [[0.0] * AUDIT_NODES, [0.0] * AUDIT_NODES]
        self._core = None        # the compiled loop doing this observer's work, if any

    def attach(self, solver) -> bool:
        """Integrate in the compiled step loop (the same nodes and arithmetic; True if it
        can: the solver runs compiled and the model has compiled energies)."""
        core = getattr(solver, "core", None)
        if self._core is None and core is not None and core.enable_audit(
                self.dissipated, self.external_work):
            self._core = core
        return self._core is not None

    def _collect(self) -> None:
        s = self._core.s
        self.dissipated, self.external_work = s.dissipated, s.external_work

    def begin(self, run: RunState) -> None:
        self._ht, self._hg, self._key = [], [], None

    def evaluate(self, dense, t0: float, t1: float, ts: np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray] | None:
        """Prepare the step [t0, t1] (its end's 2D and P, the polynomial) and, if ``ts``
        is given, return ``(ys, energies)`` there (rows per time) from the same
        interpolation and the same kernel call as the node: one of each per step,
        outputs included."""
        if self._key == (t0, t1) and ts is None:
            return None
        new = self._key != (t0, t1)
        tq = np.array(([t0, t1] if not self._ht else [t1]) if new else [], dtype=float)
        nq = tq.size
        if ts is not None:
            tq = np.concatenate([tq, ts])
        ys, yps = dense.values(tq)                    # (nodes + k, n) each
        e = self.model.energies(tq, ys, yps)          # one kernel call
        if new:
            for j in range(nq):
                if len(self._ht) == AUDIT_NODES:
                    del self._ht[0], self._hg[0]
                g = e[j]
                self._ht.append(float(tq[j]))
                self._hg.append((float(g[2]), float(g[3] + (g[4] if g.size > 4 else 0.0))))
            self._coef = audit_polynomial(self._ht, self._hg, t0, t1 - t0)
            self._key = (t0, t1)
        return (ys[nq:], e[nq:]) if ts is not None else None

    def partial(self, dense, t0: float, t1: float, t):
        """(int 2D dt, int P dt) over [t0, t] inside the accepted step [t0, t1]; ``t`` a
        float (floats returned) or an array (two arrays)."""
        h = t1 - t0
        if h == 0.0:
            z = np.zeros_like(np.asarray(t, dtype=float))
            return (0.0, 0.0) if np.ndim(t) == 0 else (z, z)
        self.evaluate(dense, t0, t1)
        m = len(self._ht)
        xs = ((np.asarray(t, dtype=float) - t0) / h).ravel()
        d = np.array([audit_integral(m, self._coef[0], float(x)) * h for x in xs])
        w = np.array([audit_integral(m, self._coef[1], float(x)) * h for x in xs])
        return (float(d[0]), float(w[0])) if np.ndim(t) == 0 else (d, w)

    def step(self, run: RunState, dense, t0: float, t1: float) -> None:
        if self._core is not None:
            self._collect()
            return
        h = t1 - t0
        if h == 0.0:
            return
        self.evaluate(dense, t0, t1)          # the whole step: x = 1 below
        m = len(self._ht)
        self.dissipated += audit_integral(m, self._coef[0], 1.0) * h
        self.external_work += audit_integral(m, self._coef[1], 1.0) * h

    def end(self, run: RunState) -> None:
        if self._core is not None:
            self._collect()

    def restart(self, run: RunState, restart) -> None:
        """The integrator restarted at a breakpoint where prescribed velocities jump: the
        supports' impulse did the work of the held masses' kinetic energy jump (the
        positions, hence W, are continuous), booked as external work."""
        self._ht, self._hg, self._key = [], [], None     # P may jump here: new nodes
        t = restart.t
        dT = (self.model.energy_scalars(t, restart.y_after)[0]
              - self.model.energy_scalars(t, restart.y_before)[0])
        if dT == 0.0:
            return
        if self._core is not None:
            self._collect()
            self._core.s.external_work += dT
        self.external_work += dT

    def state(self) -> dict[str, Any]:
        return {"diss": self.dissipated, "work": self.external_work}

    def restore(self, st: dict[str, Any]) -> None:
        self.dissipated, self.external_work = float(st["diss"]), float(st["work"])


class Sampler:
    """Samples on a uniform output grid: chosen state components, energies, their running
    integrals and the model's further output scalars (the supports' reactions).

    ``channels``: name -> state indices (e.g. ``"tip"``: the s = L node's position);
    per output time ``t`` it records each channel's values, kinetic ``T`` and elastic
    ``W`` energy (J), dissipated energy ``int 2D`` and external work ``int P`` (J) since
    the start, and ``extras``: the values of ``model.energies`` beyond the first five.
    The outputs of a step are evaluated together with the step's energy quadrature
    (:meth:`EnergyIntegrator.evaluate`) and kept as arrays per step. With forward
    sensitivities (``dense.sens``, ``run.s``) each channel's sensitivities are sampled
    at the same times (:meth:`arrays`: ``"sens"``).
    """

    name = "sampler"
    SCALARS = ("T", "W", "D", "P")
    sparse = True

    def __init__(self, model, energy: EnergyIntegrator, t_out: np.ndarray,
                 channels: dict[str, np.ndarray], n_extras: int = 0) -> None:
        self.model, self.energy = model, energy
        self.t_out = np.asarray(t_out, dtype=float)
        self.channels = {k: np.asarray(v, dtype=int).ravel() for k, v in channels.items()}
        self.n_extras = int(n_extras)
        self.k_out = 0
        self.rec: dict[str, list[np.ndarray]] = {k: [] for k in self._keys()}
        self._core = None
        #: rows (m, k * size) of the sensitivities of the sampled components (parameter
        #: by parameter), when the run has them
        self.srec: list[np.ndarray] = []

    def _keys(self) -> tuple[str, ...]:
        return ("t", *self.channels, *self.SCALARS, "extras")

    def _record(self, ts: np.ndarray, ys: np.ndarray, en: np.ndarray, diss: np.ndarray,
                work: np.ndarray) -> None:
        """ys: (k, n) states (or (k, m) with the channels' columns in order), en: (k, >= 2
        + n_extras) rows [T, W, ..., extras at the end]."""
        r = self.rec
        r["t"].append(np.asarray(ts, dtype=float))
        col = 0
        for name, idx in self.channels.items():
            r[name].append(np.array(ys[:, col:col + idx.size]))
            col += idx.size
        r["T"].append(np.array(en[:, 0], dtype=float))
        r["W"].append(np.array(en[:, 1], dtype=float))
        r["D"].append(np.asarray(diss, dtype=float))
        r["P"].append(np.asarray(work, dtype=float))
        r["extras"].append(np.array(en[:, en.shape[1] - self.n_extras:], dtype=float)
                           if self.n_extras else np.zeros((len(ts), 0)))

    def _all_indices(self) -> np.ndarray:
        return np.concatenate([*self.channels.values(), np.zeros(0, dtype=int)])

    def attach(self, solver) -> bool:
        """Sample in the compiled step loop (with the energy integrator there too)."""
        if self._core is None and self.energy.attach(solver):
            core = solver.core
            sens = self._sens_rows if solver.n_sensitivities else None
            if core.enable_sampling(self.t_out, self.k_out, self._all_indices(), self._rows,
                                    sens):
                self._core = core
        return self._core is not None

    def _rows(self, rows: np.ndarray) -> None:
        """Rows [t, channels..., T, W, int 2D, int P, extras...] from the compiled loop."""
        b = 1 + self._all_indices().size
        en = np.concatenate([rows[:, b:b + 2], rows[:, b + 4:]], axis=1)
        self._record(rows[:, 0].copy(), rows[:, 1:b], en, rows[:, b + 2].copy(),
                     rows[:, b + 3].copy())
        self.k_out += rows.shape[0]

    def _sens_rows(self, rows: np.ndarray) -> None:
        self.srec.append(np.array(rows))

    def _sens_sample(self, s: np.ndarray) -> None:
        """Rows of the sampled components' sensitivities from full ones (m, k, n)."""
        idx = self._all_indices()
        self.srec.append(s[:, :, idx].reshape(s.shape[0], -1))

    def _collect(self) -> None:
        self._core.flush_samples()

    def end(self, run: RunState) -> None:
        if self._core is not None:
            self._collect()

    def begin(self, run: RunState) -> None:
        if self.k_out == 0 and self.t_out.size and self.t_out[0] <= run.t:
            e = self.model.energies(np.array([run.t]), run.y[None, :], run.yp[None, :])
            self._record(np.array([run.t]), run.y[None, self._all_indices()], e,
                         np.zeros(1), np.zeros(1))
            if run.s is not None:
                self._sens_sample(run.s[None])
            self.k_out = 1

    def step(self, run: RunState, dense, t0: float, t1: float) -> None:
        if self._core is not None:
            self._collect()
            return
        # called before the energy integrator adds this step: its totals end at t0
        k0 = self.k_out
        slack = 1e-12 * max(1.0, abs(t1))
        k = int(np.searchsorted(self.t_out, t1 + slack, side="right"))
        if k <= k0:
            return
        ts = np.minimum(self.t_out[k0:k], t1)
        e = self.energy
        ys, en = e.evaluate(dense, t0, t1, ts)        # with the step's audit node
        dd, ww = e.partial(dense, t0, t1, ts)
        self._record(ts, ys[:, self._all_indices()], en, e.dissipated + dd,
                     e.external_work + ww)
        if dense.sens is not None:
            sy, _ = dense.sens.values(ts)
            self._sens_sample(sy.reshape(ts.size, -1, self.model.n))
        self.k_out = k

    def arrays(self) -> dict[str, np.ndarray]:
        """``t`` (n,), each channel (size, n), ``kinetic``, ``elastic``, ``dissipated``,
        ``external_work`` (n,), ``extras`` (n_extras, n)."""
        r = self.rec

        def cat(key: str, width: int = 0) -> np.ndarray:
            if r[key]:
                return np.concatenate(r[key])
            return np.zeros((0, width)) if width else np.zeros(0)

        out = {"t": cat("t")}
        for name, idx in self.channels.items():
            out[name] = cat(name, idx.size).T
        out.update(kinetic=cat("T"), elastic=cat("W"), dissipated=cat("D"),
                   external_work=cat("P"), extras=cat("extras", self.n_extras).T)
        if self.srec:          # per channel (k, size, m): the sensitivities' samples
            rows = np.concatenate(self.srec)
            m, width = rows.shape[0], self._all_indices().size
            rows = rows.reshape(m, -1, width)
            col, sens = 0, {}
            for name, idx in self.channels.items():
                sens[name] = rows[:, :, col:col + idx.size].transpose(1, 2, 0).copy()
                col += idx.size
            out["sens"] = sens
        return out

    def state(self) -> dict[str, Any]:
        a = self.arrays()
        st: dict[str, Any] = {"k_out": self.k_out, "rec_t": a["t"], "rec_T": a["kinetic"],
                              "rec_W": a["elastic"], "rec_D": a["dissipated"],
                              "rec_P": a["external_work"], "rec_extras": a["extras"].T}
        for name in self.channels:
            st["rec_" + name] = a[name].T
        return st

    def restore(self, st: dict[str, Any]) -> None:
        self.k_out = int(st["k_out"])
        r = self.rec
        for key, src in (("t", "rec_t"), ("T", "rec_T"), ("W", "rec_W"), ("D", "rec_D"),
                         ("P", "rec_P")):
            r[key] = [np.asarray(st[src], dtype=float)]
        m = r["t"][0].size
        for name, idx in self.channels.items():        # absent in an older checkpoint: NaN
            v = st.get("rec_" + name)
            r[name] = [np.asarray(v, dtype=float).reshape(-1, idx.size) if v is not None
                       and np.size(v) == m * idx.size else np.full((m, idx.size), math.nan)]
        v = st.get("rec_extras")
        r["extras"] = [np.asarray(v, dtype=float).reshape(-1, self.n_extras)
                       if v is not None and np.size(v) == m * self.n_extras
                       else np.full((m, self.n_extras), math.nan)]


class Maxima:
    """Maxima of one state component (e.g. the tip's x), located on the dense output.

    A maximum is where the matching velocity component crosses zero downwards; its time is
    refined by Brent's method on the step's interpolant. Values are reported relative to
    ``offset`` (the component's reference value: a displacement). ``positive_only`` keeps maxima
    with a positive value (the decay of a vibration about zero); ``initial`` also counts a
    release from rest at a positive value (any value without ``positive_only``: whether
    it is a maximum is decided against the vibration's centre afterwards) as a maximum at
    the start time.
    """

    name = "maxima"
    sparse = True
    #: with the compiled loop, a step where the velocity changes sign is kept for a
    #: replay (runtime.solvers.driver) instead of a return to Python for each maximum
    replay_watches = True

    def __init__(self, position_index: int, velocity_index: int, *,
                 positive_only: bool = True, initial: bool = True,
                 offset: float = 0.0) -> None:
        self.ix, self.iv = int(position_index), int(velocity_index)
        self.offset = float(offset)     # reported values are y[ix] - offset
        self.positive_only, self.initial = positive_only, initial
        self.t: list[float] = []
        self.x: list[float] = []
        self._last_t1 = math.nan         # the step last looked at (a replayed step and a
        #                                  stop may be the same step)

    def replay_times(self, t_end: float) -> np.ndarray:
        """No times: the steps it needs are those of its watch (:attr:`replay_watches`)."""
        return np.zeros(0)

    def _keep(self, x: float) -> bool:
        return x > 0 or not self.positive_only

    def begin(self, run: RunState) -> None:
        x0 = float(run.y[self.ix]) - self.offset
        if self.initial and not self.t and self._keep(x0) and (
                x0 > 0 or not self.positive_only):
            self.t.append(run.t)
            self.x.append(x0)

    def watches(self) -> list[tuple[int, float]]:
        return [(self.iv, -1.0)]

    def step(self, run: RunState, dense, t0: float, t1: float) -> None:
        if t1 == self._last_t1:
            return
        self._last_t1 = t1
        v_new = float(run.y[self.iv])
        # the velocity at the step's start, from the step's own interpolant: the previous
        # call may lie many steps back in the compiled loop
        v_old = float(dense(t0)[self.iv]) if v_new <= 0.0 and t1 > t0 else 0.0
        if v_old > 0.0 >= v_new:
            tk = t1 if v_new == 0.0 else bracketed_root(
                lambda s: float(dense(s)[self.iv]), t0, t1, v_old, v_new,
                xtol=1e-14)
            xk = float(dense(tk)[self.ix]) - self.offset
            if self._keep(xk):
                self.t.append(tk)
                self.x.append(xk)

    def state(self) -> dict[str, Any]:
        return {"peaks_t": np.array(self.t), "peaks_x": np.array(self.x)}

    def restore(self, st: dict[str, Any]) -> None:
        self.t = [float(v) for v in st["peaks_t"]]
        self.x = [float(v) for v in st["peaks_x"]]


class Snapshots:
    """Full states every ``every`` seconds (for VTK), handed to ``sink(t, y, yp)`` at once
    (the state and its rate at that time: the viscous resultants need both)."""

    name = "snapshots"
    sparse = True

    def __init__(self, every: float,
                 sink: Callable[[float, np.ndarray, np.ndarray], object]) -> None:
        self.every, self.sink = float(every), sink
        self.next = math.nan

    def begin(self, run: RunState) -> None:
        if not math.isfinite(self.next):
            self.sink(run.t, run.y.copy(), run.yp.copy())
            self.next = run.t + self.every

    def replay_times(self, t_end: float) -> np.ndarray:
        """The snapshot times still to come (as :meth:`step` steps through them)."""
        out, t = [], self.next
        while t <= t_end:
            out.append(t)
            t += self.every
        return np.array(out)

    def step(self, run: RunState, dense, t0: float, t1: float) -> None:
        while self.next <= t1:
            self.sink(self.next, np.array(dense(self.next)),
                      np.array(dense.derivative(self.next)))
            self.next += self.every

    def state(self) -> dict[str, Any]:
        return {"snap_next": self.next}

    def restore(self, st: dict[str, Any]) -> None:
        self.next = float(st.get("snap_next", math.nan))


class Centreline:
    """The deformed centreline: node positions (3, N+1) at the times ``t_frames`` (s), read
    from the step's interpolant like :class:`Snapshots`, for plots and animations of a run.

    Only positions are kept (3 (N+1) numbers a frame), so a run stores a modest grid of
    them (``simulation.centreline_frames``) rather than full states. ``phi_index``
    (N+1, 3): the state indices of the node positions. Any other state indices (n, c)
    are recorded the same way, (c, n) a frame (an assembly's bodies: node position and
    quaternion); ``key`` names them in a checkpoint (one key per instance).
    """

    name = "centreline"
    sparse = True

    def __init__(self, t_frames: np.ndarray, phi_index: np.ndarray,
                 key: str = "centreline") -> None:
        self.t_frames = np.asarray(t_frames, dtype=float)
        self.idx = np.asarray(phi_index, dtype=int)
        self.key = key
        self.k = 0
        self.rec: list[np.ndarray] = []
        #: the positions' sensitivities (k, 3, N+1) per frame, when the run has them
        self.srec: list[np.ndarray] = []
        self._core = None            # the compiled loop taking the frames, if any
        self._frames: np.ndarray | None = None

    def into_core(self, solver) -> bool:
        """Take the frames inside the compiled loop (its frame grid,
        ``CoreLink.enable_frames``: the same interpolation at the same times as
        :meth:`step`, so the same bits) instead of from replayed steps; True if it does
        (not with sensitivities, nor when the grid is taken)."""
        self._core = self._frames = None
        core = getattr(solver, "core", None)
        if core is None or solver.n_sensitivities or self.k >= self.t_frames.size:
            return False
        frames = np.zeros((self.t_frames.size, self.idx.size))
        if not core.enable_frames(self.t_frames, self.k, self.idx.ravel(), frames):
            return False
        self._core, self._frames = core, frames
        return True

    def _collect(self) -> None:
        done = self._core.grid_done
        for j in range(self.k, done):
            self.rec.append(self._frames[j].reshape(self.idx.shape).T.copy())
        self.k = max(self.k, done)

    def begin(self, run: RunState) -> None:
        if self.k == 0 and self.t_frames.size and self.t_frames[0] <= run.t:
            self.rec.append(np.array(run.y[self.idx].T))
            if run.s is not None:
                self.srec.append(np.array(run.s[:, self.idx].transpose(0, 2, 1)))
            self.k = 1

    def replay_times(self, t_end: float) -> np.ndarray:
        """The frame times still to come."""
        return self.t_frames[self.k:]

    def step(self, run: RunState, dense, t0: float, t1: float) -> None:
        if self._core is not None:
            self._collect()
            return
        k = int(np.searchsorted(self.t_frames, t1 + 1e-12 * max(1.0, abs(t1)), side="right"))
        if k <= self.k:
            return
        # dense.values: kv_interp, the arithmetic of the compiled loop's frames (into_core)
        ys, _ = dense.values(np.minimum(self.t_frames[self.k:k], t1))
        for j, t in enumerate(self.t_frames[self.k:k]):
            self.rec.append(np.array(ys[j][self.idx].T))
            if dense.sens is not None:
                s = np.asarray(dense.sens(min(t, t1))).reshape(-1, run.y.size)
                self.srec.append(np.array(s[:, self.idx].transpose(0, 2, 1)))
        self.k = max(self.k, k)

    def end(self, run: RunState) -> None:
        if self._core is not None:
            self._collect()

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """``(t, positions)``: the frame times reached (m,) and positions (m, 3, N+1), m."""
        if self._core is not None:
            self._collect()
        pos = (np.stack(self.rec) if self.rec
               else np.zeros((0, self.idx.shape[1], self.idx.shape[0])))
        return self.t_frames[:self.k].copy(), pos

    def state(self) -> dict[str, Any]:
        return {f"{self.key}_k": self.k, f"{self.key}_positions": self.arrays()[1]}

    def restore(self, st: dict[str, Any]) -> None:
        self.k = int(st.get(f"{self.key}_k", 0))
        pos = st.get(f"{self.key}_positions")
        shape = (self.k, self.idx.shape[1], self.idx.shape[0])
        # a checkpoint without frames (an older kvrod): the frames before it are unknown
        self.rec = list(np.asarray(pos, dtype=float).reshape(shape)
                        if pos is not None and np.size(pos) == math.prod(shape)
                        else np.full(shape, math.nan))


class Progress:
    """Calls ``callback(t)`` after accepted steps (a progress bar): after every step
    without the compiled loop, else at its stops (at least every ``1/ticks`` of the
    run)."""

    name = "progress"
    sparse = True
    ticks = 100

    def __init__(self, callback: Callable[[float], object]) -> None:
        self.callback = callback

    def step(self, run: RunState, dense, t0: float, t1: float) -> None:
        self.callback(t1)
